"""Trials per minute of a quick sweep: 1 and 2 local worker processes, and a local Dask cluster.

The sweep is the silent paper's Fig. 5 grid (d0 in {5, 8, 11}) x ``--seeds`` seeds,
cut to ``--steps`` steps per trial. Every executor runs the same trials into its own
folder (a fresh store each); the script checks that the tables agree trial by trial
(every column but the wall times) and reports trials per minute and the speed-up over
one worker. The machine (and its load average, since shared machines vary) is
recorded with the results.

Usage::

    nice python benchmarks/bench_sweep.py [--seeds 4] [--steps 600] [--repeat 1]

Writes ``benchmarks/results/sweep.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time
from pathlib import Path

import pyarrow.parquet as pq

from _machine import machine
from tether.config import load_scenario, scenario_from_dict
from tether.experiments.sweep import run_sweep

#: columns that measure the machine, not the trial
TIMING = {"wall_time_s", "planning_time_mean_s", "planning_time_max_s", "run_dir"}
#: (name, executor, workers)
SETUPS = (("1 local worker", "processes", 1), ("2 local workers", "processes", 2),
          ("Dask LocalCluster, 2 workers", "dask", 2))  # fmt: skip


def _table(path: Path) -> dict[str, dict]:
    rows = pq.read_table(path).to_pylist()
    return {r["trial_id"]: {k: v for k, v in r.items() if k not in TIMING} for r in rows}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--steps", type=int, default=600)
    ap.add_argument("--repeat", type=int, default=1, help="runs per setup (best is kept)")
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" / "sweep.json"))
    args = ap.parse_args()

    data = load_scenario("silent_paper").model_dump(mode="json")
    data["sim"]["max_steps"] = args.steps
    scenario = scenario_from_dict(data, "silent_paper (benchmark)")
    load_before = os.getloadavg()

    results, reference = [], None
    with tempfile.TemporaryDirectory() as tmp:
        for name, executor, workers in SETUPS:
            walls = []
            for k in range(args.repeat):
                folder = Path(tmp) / f"{executor}-{workers}-{k}"
                tic = time.perf_counter()
                out = run_sweep(
                    scenario, folder, seeds=args.seeds, executor=executor, workers=workers
                )
                walls.append(time.perf_counter() - tic)
                table = _table(out.table)
                reference = reference or table
            n_trials = len(table)
            wall = min(walls)
            results.append(
                {
                    "setup": name,
                    "executor": executor,
                    "workers": workers,
                    "trials": n_trials,
                    "wall_s": round(wall, 3),
                    "trials_per_min": round(60 * n_trials / wall, 1),
                    "same_table_as_1_worker": table == reference,
                }
            )
            print(f"{name:<30} {n_trials} trials {wall:7.2f} s {60 * n_trials / wall:7.1f}/min")
    base = results[0]["wall_s"]
    for r in results:
        r["speedup_vs_1_worker"] = round(base / r["wall_s"], 2)
    report = {
        "benchmark": "trials per minute of a quick sweep (silent_paper d0 grid x seeds)",
        "command": f"nice python benchmarks/bench_sweep.py --seeds {args.seeds} "
        f"--steps {args.steps} --repeat {args.repeat}",
        "machine": {
            **machine(),
            "load_average_1_5_15_before": [round(x, 2) for x in load_before],
            "load_average_1_5_15_after": [round(x, 2) for x in os.getloadavg()],
        },  # fmt: skip
        "settings": {"seeds": args.seeds, "steps": args.steps, "repeat": args.repeat},
        "results": results,
    }
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(report, indent=1) + "\n")
    for r in results:
        print(f"{r['setup']:<30} speed-up {r['speedup_vs_1_worker']:.2f}x, same table: "
              f"{r['same_table_as_1_worker']}")  # fmt: skip
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
