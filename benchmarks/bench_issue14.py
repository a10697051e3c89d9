"""Every row of issue 14's performance table, old tree against new tree in the same run.

Each row is one probe of :mod:`issue14_probes` run in a fresh subprocess per tree
(``PYTHONPATH=<tree>/src``), the trees alternating (old new, new old, ...) so that a
load that drifts hits both alike. With ``--clock cpu`` (the default: the machine is
shared) the probes' ``time.perf_counter`` is ``time.process_time``. The headline of
each row is compared with the issue's goal; results go to
``benchmarks/results/issue14.json`` with the machine, both git hashes and the load.

    python benchmarks/bench_issue14.py --old-root /work/base [--mid main /tmp/main]
        [--rows step35_free ...] [--pairs 2] [--clock cpu|wall] [--out PATH]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

HERE = Path(__file__).resolve().parent
OUT = HERE / "results" / "issue14.json"
CPU_CLOCK = (
    "import runpy, sys, time\n"
    "time.perf_counter = time.process_time\n"
    "sys.argv = sys.argv[1:]\n"
    "runpy.run_path(sys.argv[0], run_name='__main__')\n"
)

# name: (probe, kwargs, headline key, goal, "<=" or ">=")
ROWS: dict[str, tuple[str, dict, str, float, str]] = {
    "step35_free": ("step", {"world": "free", "n": 35, "repeat": 2000}, "step_s", 50e-6, "<="),
    "step35_town": ("step", {"world": "town", "n": 35, "repeat": 2000}, "step_s", 100e-6, "<="),
    "step1000_free": ("step", {"world": "free", "n": 1000, "repeat": 5}, "step_s", 5e-3, "<="),
    "step10000_free": ("step", {"world": "free", "n": 10000, "repeat": 2}, "step_s", 0.1, "<="),
    "silent10000": ("silent", {"n": 10000, "steps": 3}, "steps_per_s", 10.0, ">="),
    "silent20": ("silent", {"n": 20, "steps": 200}, "ms_per_step_whole", 0.2, "<="),
    "placement100k": ("placement", {"n": 100_000}, "seconds", 30.0, "<="),
    "placement1000": ("placement", {"n": 1000}, "seconds", 30.0, "<="),
    "steiner": (
        "steiner",
        {"seed": 0, "count": 12, "repeat": 3},
        "median_exact_over_mehlhorn",
        1.0,
        "<=",
    ),
    "ilp": ("ilp", {"seeds": [0, 1, 2, 3, 4], "time_limit": 60.0}, "scip_median_s", 0.5, "<="),
    "recurrent_grass": (
        "run",
        {"scenario": "recurrent_grass", "sets": []},
        "e2e_cpu_s",  # the goal is wall time; on a loaded machine CPU time is the fair proxy
        10.0,
        "<=",
    ),
}
ONLY_NEW = {"placement100k"}  # the old placement did not finish (10,000 robots: 19 min)
# one run per tree (long probes); recurrent_grass (about 10 s now) takes --pairs like the rest
SINGLE = {"step10000_free", "placement100k", "silent10000"}


def git_hash(root: Path) -> str:
    out = subprocess.run(["git", "-C", str(root), "rev-parse", "HEAD"], capture_output=True)
    return out.stdout.decode().strip()


def probe(root: Path, name: str, kwargs: dict, clock: str) -> dict:
    """Run one probe with ``root``'s tether; its JSON result plus process stats."""
    # TETHER_JIT=on: the compiled kernels from the first call (warm numba's cache first:
    # python -m tether.continuous.kernels); the old tree has none and ignores it.
    env = dict(os.environ, PYTHONPATH=str(root / "src"), TETHER_TREE=str(root), TETHER_JIT="on")
    script = str(HERE / "issue14_probes.py")
    py = [sys.executable] if clock == "wall" else [sys.executable, "-c", CPU_CLOCK]
    load0 = os.getloadavg()[0]
    t0 = time.perf_counter()
    out = subprocess.run(
        [*py, script, name, json.dumps(kwargs)], env=env, capture_output=True, text=True
    )
    if out.returncode != 0:
        raise SystemExit(f"{root} {name} {kwargs} failed:\n{out.stderr[-3000:]}")
    res = json.loads(out.stdout.strip().splitlines()[-1])
    res["_process_wall_s"] = time.perf_counter() - t0
    res["_load"] = [load0, os.getloadavg()[0]]
    return res


def headline(row: str, res: dict) -> float:
    """The row's headline number from one probe result."""
    if row == "ilp":
        return statistics.median(r["scip_s"] for r in res["rows"])
    key = ROWS[row][2]
    return float(res[key])


def extra(row: str, res: dict) -> dict[str, Any]:
    """Secondary numbers shown with the headline."""
    if row == "ilp":
        rs = res["rows"]
        return {
            "scip_max_s": max(r["scip_s"] for r in rs),
            "highs_median_s": statistics.median(r["highs_s"] for r in rs),
            "highs_max_s": max(r["highs_s"] for r in rs),
            "all_proven": all(r["scip_proven_optimal"] and r["highs_proven_optimal"] for r in rs),
        }
    if row.startswith("step"):
        return {k: res.get(k) for k in ("weights_s", "eigen_s", "gradient_s", "links")}
    if row.startswith("silent"):
        return {k: res.get(k) for k in ("ms_per_step", "ms_sense", "ms_strategy", "ms_metrics")}
    if row == "steiner":
        return {
            "median_exact_s": res["median_exact_s"],
            "median_mehlhorn_s": res["median_mehlhorn_s"],
            "costs": [r["exact_cost"] for r in res["rows"]],
        }
    if row == "recurrent_grass":
        return {k: res.get(k) for k in ("e2e_wall_s", "run_wall_s", "steps")}
    return {}


def measure(row: str, trees: dict[str, Path], pairs: int, clock: str) -> dict:
    """One row on every tree (the last one is "new": it is judged against the goal)."""
    name, kwargs, key, goal, sense = ROWS[row]
    sides = ["new"] if row in ONLY_NEW else list(trees)
    runs: dict[str, list[dict]] = {s: [] for s in sides}
    for i in range(1 if row in SINGLE else pairs):
        for side in sides if i % 2 == 0 else sides[::-1]:
            res = probe(trees[side], name, kwargs, clock)
            runs[side].append(res)
            print(f"  {row} {side}: {headline(row, res):.6g}", flush=True)
    out: dict[str, Any] = {"probe": name, "kwargs": kwargs, "headline": key, "goal": goal}
    out["goal_sense"] = sense
    for side in sides:
        vals = [headline(row, r) for r in runs[side]]
        out[side] = statistics.median(vals)
        out[f"{side}_all"] = vals
        out[f"{side}_extra"] = extra(row, runs[side][-1])
        out[f"{side}_runs"] = runs[side]
    new_v = out["new"]
    out["met"] = new_v <= goal if sense == "<=" else new_v >= goal
    if row == "ilp":
        ex = out["new_extra"]
        out["met"] = out["met"] and ex["scip_max_s"] <= 2.0
    return out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old-root", type=Path, required=True)
    ap.add_argument("--new-root", type=Path, default=HERE.parent)
    ap.add_argument(
        "--mid",
        nargs=2,
        metavar=("NAME", "ROOT"),
        help="a third tree timed between old and new (e.g. main 1a3426c)",
    )
    ap.add_argument("--rows", nargs="+", default=list(ROWS), choices=list(ROWS))
    ap.add_argument("--pairs", type=int, default=2)
    ap.add_argument("--clock", choices=["cpu", "wall"], default="cpu")
    ap.add_argument("--out", type=Path, default=OUT)
    ap.add_argument("--conditions", default="", help="free text: load on the machine etc.")
    a = ap.parse_args(argv)
    sys.path.insert(0, str(HERE))
    from _machine import machine

    trees = {"old": a.old_root.resolve()}
    if a.mid:
        trees[a.mid[0]] = Path(a.mid[1]).resolve()
    trees["new"] = a.new_root.resolve()
    result = json.loads(a.out.read_text()) if a.out.exists() else {"rows": {}}
    result.update(
        {
            "what": "issue 14 table: old tree vs new tree, interleaved, one subprocess per probe",
            "machine": machine(),
            "trees": {name: {"root": str(p), "git_hash": git_hash(p)} for name, p in trees.items()},
            "clock": a.clock,
            "conditions": a.conditions,
        }
    )
    for row in a.rows:
        print(f"[{row}]", flush=True)
        res = measure(row, trees, a.pairs, a.clock)
        res["clock"] = a.clock
        res["date"] = time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())
        result["rows"][row] = res
        a.out.parent.mkdir(parents=True, exist_ok=True)
        a.out.write_text(json.dumps(result, indent=1) + "\n")
        vals = "  ".join(f"{t} {res[t]:.4g}" for t in trees if t in res)
        print(
            f"{row:16s} goal {res['goal_sense']} {res['goal']:.4g}  {vals}  met {res['met']}",
            flush=True,
        )


if __name__ == "__main__":
    main(sys.argv[1:])
