"""Time two source trees of tether against each other in one run (e.g. before / after a refactor).

Each tree is timed with its OWN benchmark script (the APIs may differ between them):
``python <root>/benchmarks/bench_<name>.py ... --out <tmp json>`` with
``PYTHONPATH=<root>/src``, in a fresh subprocess. The old and new runs alternate
(old, new, new, old, old, new, ...: interleaved pairs, the first of each pair
alternating so that a load that drifts during the run hits both trees alike), ``k``
pairs in all. Rows are matched on their configuration (map, strategy, team size,
steps; world, robots, solver) and each timing is reduced to its median over the
``k`` runs of each tree; the ratio is new / old (above 1 = the new tree is slower).

Benchmarks:

``exploration``
    ``bench_exploration.py --steps 300`` on the three shared maps: ``wall_time_s``
    per (map, strategy), with the simulator's own split (move, sense, comm, strategy).
``continuous_step``
    ``bench_continuous_step.py`` at its default sizes (10 to 10,000 robots): per
    (world, robots, solver) the control step and its parts (weights, eigenpair or
    estimator, gradient). A script without ``--out`` (the old one) is run from a
    temporary copy and its default output, ``results/`` beside the script, is read.
``run``
    ``tether run <scenario> --no-figures`` end to end for a few built-in scenarios:
    the process's wall time (start-up and imports included), the run's own
    ``wall_time_s`` from its ``summary.json``, and their difference (start-up,
    loading, writing).
``all``
    The three above, in that order.

Every subprocess records the 1-minute load average before and after it and its CPU
time (user + system), so that a comparison made while other jobs run can be judged.
With ``--clock cpu`` the scripts run with ``time.perf_counter`` replaced by
``time.process_time`` (both trees' benchmarks and simulators time themselves with
``time.perf_counter()``), so every row is CPU time of the process instead of wall
time: less sensitive to other jobs on the machine (not immune: they share caches
and memory bandwidth), and blind to time spent waiting (there is none in these
single-process benchmarks). For ``run``, the headline is then the process's CPU time.
Results go to ``benchmarks/results/compare_refactor.json`` (one section per
benchmark, merged into the file if it exists) with the machine and both git hashes.

    python benchmarks/compare_trees.py --old-root /work/base --new-root . exploration
    python benchmarks/compare_trees.py --old-root /work/base --new-root . all
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
OUT = HERE / "results" / "compare_refactor.json"
THRESHOLD = 1.05  # the limit: no slowdown over 5 %

RUN_SCENARIOS = ["silent_demo", "connectivity_empty", "connectivity_town", "recurrent_demo"]
MAPS = ["offices", "grass", "open"]

# Which fields identify a row, and which are timings to compare, per benchmark.
KEYS = {
    "exploration": ("map", "strategy", "n_robots", "steps"),
    "continuous_step": ("world", "n_robots", "solver"),
    "run": ("scenario",),
}
HEADLINE = {"exploration": "wall_time_s", "continuous_step": "step_s", "run": "e2e_s"}
# Run a script with time.perf_counter measuring the process's CPU time (--clock cpu).
CPU_CLOCK = (
    "import os, runpy, sys, time\n"
    "time.perf_counter = time.process_time\n"
    "sys.argv = sys.argv[1:]\n"
    "sys.path.insert(0, os.path.dirname(os.path.abspath(sys.argv[0])))\n"
    "runpy.run_path(sys.argv[0], run_name='__main__')\n"
)
# Values that must agree between the trees for the rows to be the same problem.
SAME = {
    "exploration": ("plans", "final_explored_fraction"),
    "continuous_step": ("links", "active_links"),
    "run": ("steps",),
}


# -- the trees -----------------------------------------------------------------------------
def git_hash(root: Path) -> dict[str, Any]:
    """Commit of ``root`` and whether its work tree differs from it."""

    def git(*args: str) -> str:
        out = subprocess.run(["git", "-C", str(root), *args], capture_output=True, text=True)
        return out.stdout.strip() if out.returncode == 0 else ""

    return {
        "root": str(root),
        "git_hash": git("rev-parse", "HEAD") or None,
        "dirty": bool(git("status", "--porcelain", "--untracked-files=no")),
    }


def tree_env(root: Path) -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = str(root / "src")
    return env


def check_tree(root: Path) -> None:
    """Fail unless ``PYTHONPATH=<root>/src`` really imports that tree's ``tether``."""
    code = "import tether, sys; sys.stdout.write(tether.__file__)"
    out = subprocess.run(
        [sys.executable, "-c", code], env=tree_env(root), capture_output=True, text=True
    )
    got = Path(out.stdout.strip()).resolve()
    if out.returncode != 0 or (root / "src").resolve() not in got.parents:
        raise SystemExit(f"PYTHONPATH={root}/src imports tether from {got}: {out.stderr[-500:]}")


def supports(script: Path, option: str, root: Path) -> bool:
    """Whether ``script --help`` lists ``option``."""
    out = subprocess.run(
        [sys.executable, str(script), "--help"], env=tree_env(root), capture_output=True, text=True
    )
    return option in out.stdout


# -- one timed subprocess ------------------------------------------------------------------
def timed_process(cmd: list[str], env: dict[str, str], cwd: Path, log: Path) -> dict[str, float]:
    """Run ``cmd``; its wall time, CPU time and the load average around it."""
    load0 = os.getloadavg()[0]
    ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    with log.open("w") as fh:
        proc = subprocess.run(cmd, env=env, cwd=cwd, stdout=fh, stderr=subprocess.STDOUT)
    wall = time.perf_counter() - t0
    ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise SystemExit(f"failed ({proc.returncode}): {' '.join(cmd)}\n{log.read_text()[-3000:]}")
    cpu = (ru1.ru_utime - ru0.ru_utime) + (ru1.ru_stime - ru0.ru_stime)
    return {"wall_s": wall, "cpu_s": cpu, "load_before": load0, "load_after": os.getloadavg()[0]}


def bench_script(
    name: str, root: Path, args: list[str], tmp: Path, tag: str, clock: str = "wall"
) -> tuple[list[dict], dict]:
    """Run ``<root>/benchmarks/bench_<name>.py args`` once; its result rows and process stats."""
    script = root / "benchmarks" / f"bench_{name}.py"
    out = tmp / f"{tag}.json"
    python = [sys.executable] if clock == "wall" else [sys.executable, "-c", CPU_CLOCK]
    if supports(script, "--out", root):
        cmd = [*python, str(script), *args, "--out", str(out)]
        cwd = root
    else:  # writes results/<name>.json beside itself: run a copy, read it there
        copy_dir = tmp / f"{tag}_script"
        copy_dir.mkdir()
        shutil.copy2(script, copy_dir / script.name)
        cmd = [*python, str(copy_dir / script.name), *args]
        cwd = copy_dir
        out = copy_dir / "results" / f"{name}.json"
    proc = timed_process(cmd, tree_env(root), cwd, tmp / f"{tag}.log")
    return json.loads(out.read_text())["results"], proc


def run_scenarios(root: Path, scenarios: list[str], tmp: Path, tag: str) -> tuple[list, dict]:
    """``tether run <scenario> --no-figures`` for each scenario, timed end to end."""
    rows = []
    total = {"wall_s": 0.0, "cpu_s": 0.0, "load_before": os.getloadavg()[0]}
    for sc in scenarios:
        folder = tmp / f"{tag}_{sc}"
        cmd = [
            sys.executable,
            "-c",
            "from tether.cli import main; main()",
            "run",
            sc,
            "--no-figures",
            "--out",
            str(folder),
        ]
        proc = timed_process(cmd, tree_env(root), tmp, tmp / f"{tag}_{sc}.log")
        summary = json.loads((folder / "summary.json").read_text())
        shutil.rmtree(folder)
        rows.append(
            {
                "scenario": sc,
                "steps": summary.get("steps"),
                "e2e_s": proc["wall_s"],
                "e2e_cpu_s": proc["cpu_s"],
                "run_wall_s": summary["wall_time_s"],
                "startup_and_io_s": proc["wall_s"] - summary["wall_time_s"],
            }
        )
        total["wall_s"] += proc["wall_s"]
        total["cpu_s"] += proc["cpu_s"]
    total["load_after"] = os.getloadavg()[0]
    return rows, total


# -- rows ------------------------------------------------------------------------------------
def flatten(row: dict) -> dict:
    """Timing fields of one row (nested ``time_split_s`` flattened as ``split_<key>_s``)."""
    out = {}
    for k, v in row.items():
        if k == "time_split_s":
            out.update({f"split_{kk}_s": vv for kk, vv in v.items()})
        elif isinstance(v, (int, float)) and not isinstance(v, bool) and k.endswith("_s"):
            out[k] = v
    return out


def combine(name: str, runs: dict[str, list[list[dict]]]) -> list[dict]:
    """Per matched row: medians of every timing over the runs of each tree, and ratios."""
    keys = KEYS[name]

    def index(rows: list[dict]) -> dict[tuple, dict]:
        return {tuple(r.get(k) for k in keys): r for r in rows}

    old = [index(r) for r in runs["old"]]
    new = [index(r) for r in runs["new"]]
    order = list(old[0])
    matched = []
    for key in order:
        if not all(key in r for r in old + new):
            continue
        o0, n0 = old[0][key], new[0][key]
        fields = sorted(set(flatten(o0)) & set(flatten(n0)))
        row: dict[str, Any] = dict(zip(keys, key, strict=True))
        row["runs"] = {"old": len(old), "new": len(new)}
        mismatch = {f: [o0.get(f), n0.get(f)] for f in SAME[name] if o0.get(f) != n0.get(f)}
        if mismatch:
            row["differs"] = mismatch
        for f in fields:
            o = statistics.median(flatten(r[key])[f] for r in old)
            n = statistics.median(flatten(r[key])[f] for r in new)
            row[f] = {
                "old": o,
                "new": n,
                "ratio": n / o if o else None,
                "old_all": [flatten(r[key])[f] for r in old],
                "new_all": [flatten(r[key])[f] for r in new],
            }
        matched.append(row)
    unmatched = set(old[0]) ^ set(new[0])
    if unmatched:
        print(f"rows not in both trees (not compared): {sorted(map(str, unmatched))}")
    return matched


def headline(name: str, clock: str) -> str:
    return "e2e_cpu_s" if name == "run" and clock == "cpu" else HEADLINE[name]


def table(name: str, rows: list[dict], head: str) -> str:
    """Text table: headline timing old / new medians and ratio, and the ratios of its parts."""
    keys = KEYS[name]
    parts = {
        "exploration": ["split_move_s", "split_sense_s", "split_comm_s", "split_strategy_s"],
        "continuous_step": ["weights_s", "eigen_s", "estimator_s", "gradient_s"],
        "run": ["run_wall_s", "startup_and_io_s"],
    }[name]
    scale, unit = (1e6, "us") if name == "continuous_step" else (1.0, "s")
    lines = [
        f"{' / '.join(keys):40s} {head + ' old':>14s} {'new':>10s} {'ratio':>6s}  parts new/old",
    ]
    for r in rows:
        label = " / ".join(str(r[k]) for k in keys)
        h = r[head]
        flag = "  SLOWER" if h["ratio"] and h["ratio"] > THRESHOLD else ""
        part = "  ".join(
            f"{p.removeprefix('split_').removesuffix('_s')} {r[p]['ratio']:.2f}"
            for p in parts
            if p in r and r[p]["ratio"] is not None
        )
        differs = f"  differs {r['differs']}" if "differs" in r else ""
        lines.append(
            f"{label:40s} {h['old'] * scale:11.3f} {unit:2s} {h['new'] * scale:10.3f} "
            f"{h['ratio']:6.3f}  {part}{flag}{differs}"
        )
    return "\n".join(lines)


# -- one benchmark ---------------------------------------------------------------------------
def compare(name: str, old: Path, new: Path, pairs: int, args: argparse.Namespace) -> dict:
    trees = {"old": old, "new": new}
    if name == "exploration":
        bench_args = ["--steps", str(args.steps), "--maps", *args.maps]
    elif name == "continuous_step":
        bench_args = ["--quick"] if args.quick else []
    else:
        bench_args = args.scenarios
    runs: dict[str, list] = {"old": [], "new": []}
    procs: dict[str, list] = {"old": [], "new": []}
    t_start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix=f"compare_{name}_") as td:
        tmp = Path(td)
        for i in range(pairs):
            for side in ("old", "new") if i % 2 == 0 else ("new", "old"):
                tag = f"{side}{i}"
                print(f"[{name}] pair {i + 1}/{pairs}: {side} ...", end=" ", flush=True)
                if name == "run":
                    rows, proc = run_scenarios(trees[side], bench_args, tmp, tag)
                else:
                    rows, proc = bench_script(name, trees[side], bench_args, tmp, tag, args.clock)
                runs[side].append(rows)
                procs[side].append(proc)
                print(
                    f"{proc['wall_s']:.1f} s wall, {proc['cpu_s']:.1f} s CPU, "
                    f"load {proc['load_before']:.2f} -> {proc['load_after']:.2f}",
                    flush=True,
                )
    rows = combine(name, runs)
    head = headline(name, args.clock)
    loads = [p[k] for side in procs.values() for p in side for k in ("load_before", "load_after")]
    section = {
        "benchmark": name,
        "arguments": bench_args,
        "pairs": pairs,
        "order": "interleaved pairs, first of each pair alternating: old new, new old, ...",
        "ratio": "new median / old median (above 1: new is slower)",
        "threshold": THRESHOLD,
        "clock": args.clock,
        "headline": head,
        "duration_s": round(time.perf_counter() - t_start, 1),
        "load_average_1min": {
            "min": min(loads),
            "median": statistics.median(loads),
            "max": max(loads),
        },
        "processes": procs,
        "process_median": {
            side: {
                "wall_s": statistics.median(p["wall_s"] for p in procs[side]),
                "cpu_s": statistics.median(p["cpu_s"] for p in procs[side]),
            }
            for side in procs
        },
        "slower_rows": [
            {k: r[k] for k in KEYS[name]}
            for r in rows
            if r[head]["ratio"] and r[head]["ratio"] > THRESHOLD
        ],
        "rows": rows,
    }
    pm = section["process_median"]
    print(table(name, rows, head))
    print(
        f"whole process, median: old {pm['old']['wall_s']:.1f} s ({pm['old']['cpu_s']:.1f} s CPU), "
        f"new {pm['new']['wall_s']:.1f} s ({pm['new']['cpu_s']:.1f} s CPU); "
        f"load average {section['load_average_1min']}"
    )
    return section


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("benchmark", choices=["exploration", "continuous_step", "run", "all"])
    ap.add_argument("--old-root", type=Path, required=True, help="checkout of the old code")
    ap.add_argument("--new-root", type=Path, default=HERE.parent, help="the new code")
    ap.add_argument("--pairs", type=int, help="old/new pairs (default 3; 5 for run)")
    ap.add_argument("--steps", type=int, default=300, help="exploration steps")
    ap.add_argument("--maps", nargs="+", default=MAPS, help="exploration maps")
    ap.add_argument("--quick", action="store_true", help="continuous_step --quick")
    ap.add_argument("--scenarios", nargs="+", default=RUN_SCENARIOS, help="for run")
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument(
        "--clock",
        choices=["wall", "cpu"],
        default="wall",
        help="what the scripts' time.perf_counter measures (cpu: the process's CPU time)",
    )
    ap.add_argument(
        "--section", help="key of the result in the JSON (default: the benchmark, +_cpu)"
    )
    a = ap.parse_args(argv)
    old, new = a.old_root.resolve(), a.new_root.resolve()
    for root in (old, new):
        check_tree(root)
    from tether.runfolder import machine  # the new tree's (this script lives in it)

    names = ["exploration", "continuous_step", "run"] if a.benchmark == "all" else [a.benchmark]
    if a.section and len(names) > 1:
        ap.error("--section names one benchmark's result")
    result = json.loads(a.out.read_text()) if a.out.exists() else {}
    result.update(
        {
            "what": "old vs new source tree, each timed with its own benchmark scripts",
            "machine": machine(),
            "old": git_hash(old),
            "new": git_hash(new),
        }
    )
    result.setdefault("benchmarks", {})
    for name in names:
        pairs = a.pairs or (5 if name == "run" else 3)
        section = compare(name, old, new, pairs, a)
        section["old"], section["new"] = result["old"], result["new"]
        section["machine"] = result["machine"]
        key = a.section or (name if a.clock == "wall" else f"{name}_{a.clock}")
        result["benchmarks"][key] = section
        a.out.parent.mkdir(parents=True, exist_ok=True)
        a.out.write_text(json.dumps(result, indent=1) + "\n")
        print(f"wrote {a.out}")
    return result


if __name__ == "__main__":
    main(sys.argv[1:])
