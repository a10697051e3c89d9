"""Wall time of one Monte Carlo sweep on each executor (serial, processes, local Dask).

The sweep is the silent paper's Fig. 5 grid (d0 in {5, 8, 11}) x ``--seeds`` seeds,
cut to ``--steps`` steps per trial. Every executor runs the same trials into its own
folder; the script checks that the summaries agree and reports the speed-up over
``serial`` (a ratio within one run, which is what to compare across machines).

Usage::

    python benchmarks/bench_sweep.py [--seeds 4] [--steps 600] [--workers 2]

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

KEYS = ("connected_all_steps", "steps", "min_links", "collisions")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=4)
    ap.add_argument("--steps", type=int, default=600)
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" / "sweep.json"))
    args = ap.parse_args()

    data = load_scenario("silent_paper").model_dump(mode="json")
    data["sim"]["max_steps"] = args.steps
    scenario = scenario_from_dict(data, "silent_paper (benchmark)")
    n_trials = len(scenario.sweep.get("strategy.params.d0_m", [None])) * args.seeds

    results, reference = [], None
    with tempfile.TemporaryDirectory() as tmp:
        for executor in ("serial", "processes", "dask"):
            tic = time.perf_counter()
            out = run_sweep(
                scenario,
                Path(tmp) / executor,
                seeds=args.seeds,
                executor=executor,
                workers=args.workers,
            )
            wall = time.perf_counter() - tic
            rows = sorted(
                pq.read_table(out.table).to_pylist(),
                key=lambda r: (r["param:strategy.params.d0_m"], r["seed"]),
            )
            summary = [{k: r[k] for k in KEYS} for r in rows]
            reference = reference or summary
            results.append(
                {
                    "executor": executor,
                    "workers": 1 if executor == "serial" else args.workers,
                    "trials": n_trials,
                    "wall_s": round(wall, 3),
                    "same_results_as_serial": summary == reference,
                }
            )
            print(f"{executor:<10} {n_trials} trials  {wall:7.2f} s")
    base = results[0]["wall_s"]
    for r in results:
        r["speedup_vs_serial"] = round(base / r["wall_s"], 2)
    report = {
        "benchmark": "sweep executors (silent_paper grid x seeds)",
        "machine": machine(),
        "settings": {"seeds": args.seeds, "steps": args.steps, "workers": args.workers},
        "results": results,
    }
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(report, indent=1))
    for r in results:
        print(f"{r['executor']:<10} speed-up {r['speedup_vs_serial']:.2f}x, same results: "
              f"{r['same_results_as_serial']}")  # fmt: skip
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
