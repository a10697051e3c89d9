"""Fuzz every built-in scenario and paper campaign through ``tether validate`` and ``run``.

Draws ``--cases`` mutated scenarios with hypothesis (``tests/_fuzz.py``: keys deleted, wrong
types, extreme numbers, unicode, deep nesting, aliases and alias bombs, YAML tags, duplicate
keys), runs each through ``validate`` then ``run`` (2 steps, numpy paths, in this process,
each command bounded by 120 s) and prints the counts: refused in one line, ran, and the
broken promises (tracebacks, exit code 1, hangs, multi-line errors, validate/run
disagreements), with the first cases of each kind. Writes JSON with the machine to
``benchmarks/results/fuzz_scenarios.json``; ``--table`` prints that file's counts as the
Markdown table docs/reference/robustness.md holds (without fuzzing).

    python benchmarks/fuzz_scenarios.py --cases 2500 --seed 0
    python benchmarks/fuzz_scenarios.py --table
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import sys
import tempfile
import time
from collections import Counter
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
os.environ.setdefault("TETHER_JIT", "0")

from hypothesis import HealthCheck, Phase, given, seed, settings  # noqa: E402

import _fuzz  # noqa: E402
from tether.runfolder import machine  # noqa: E402

RESULTS = ROOT / "benchmarks" / "results" / "fuzz_scenarios.json"
#: what each count of the table means
MEANINGS = {
    "refused": "both commands refused it with the same one `error:` line, exit code 2",
    "ran": "both commands accepted it and the run finished (exit code 0)",
    "traceback": "a traceback was printed",
    "exit-1": "exit code 1 (an internal error)",
    "hang": f"a command ran longer than {_fuzz.HANG_S:g} s",
    "not-one-line": "a refusal that was not one `error:` line",
    "disagree": "`validate` and `run` answered differently",
}


def markdown_table(result: dict) -> str:
    """The counts of a benchmark result (its JSON) as the Markdown table the docs show."""
    counts, when = result["counts"], result["machine"]["date"][:10]
    lines = [
        f"{counts['cases']:,} cases (seed {result['seed']}, {result['seconds'] / 60:.0f} min "
        f"on {result['machine']['cpu_count']} cores, {when}):",
        "",
        "| outcome | cases |",
        "| --- | ---: |",
    ]
    lines += [f"| {MEANINGS[key]} | {counts[key]:,} |" for key in MEANINGS]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=2000)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--memory-gb", type=float, default=8.0,
                        help="address-space limit of this process (a runaway case fails, "
                        "not the machine)")  # fmt: skip
    parser.add_argument("--table", action="store_true",
                        help=f"print the Markdown table of {RESULTS.name} and stop")  # fmt: skip
    args = parser.parse_args()
    if args.table:
        print(markdown_table(json.loads(RESULTS.read_text())))
        return
    limit = int(args.memory_gb * 2**30)
    resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    counts: Counter = Counter()
    bases: Counter = Counter()
    examples: dict[str, list[str]] = {}
    work = Path(tempfile.mkdtemp(prefix="tether-fuzz-"))
    start = time.perf_counter()

    @seed(args.seed)
    @settings(max_examples=args.cases, deadline=None, database=None, phases=[Phase.generate],
              suppress_health_check=list(HealthCheck))  # fmt: skip
    @given(_fuzz.cases())
    def one(case: tuple[str, str, list[str]]) -> None:
        name, text, described = case
        kind, validate, run = _fuzz.check_case(text, work)
        counts["cases"] += 1
        counts[kind] += 1
        bases[name] += 1
        if kind not in ("refused", "ran") and len(examples.setdefault(kind, [])) < 5:
            shown = " | ".join(o.err.strip()[-400:] for o in (validate, run) if o is not None)
            examples[kind].append(f"{name} {described}: {shown}")
        if counts["cases"] % 100 == 0:
            print(f"  {counts['cases']} cases, {time.perf_counter() - start:.0f} s",
                  file=sys.stderr, flush=True)  # fmt: skip

    with _fuzz.fuzz_environment(ROOT):
        one()
    seconds = time.perf_counter() - start
    table = _fuzz.tally(counts)
    print(f"fuzz_scenarios: {args.cases} cases requested, seed {args.seed}, {seconds:.0f} s")
    for key, value in table.items():
        print(f"  {key:<14} {value}")
    print(f"  bases          {len(bases)} of {len(_fuzz.BASES)} (fewest cases: "
          f"{min(bases.values()) if bases else 0})")  # fmt: skip
    for kind, lines in examples.items():
        print(f"{kind}:")
        for line in lines:
            print(f"  {line}")
    out = RESULTS
    out.parent.mkdir(parents=True, exist_ok=True)
    result = {"machine": machine(), "seed": args.seed, "seconds": round(seconds, 1),
              "counts": table, "cases_per_base": dict(bases), "examples": examples}  # fmt: skip
    out.write_text(json.dumps(result, indent=2) + "\n")
    print(f"results: {out}")


if __name__ == "__main__":
    main()
