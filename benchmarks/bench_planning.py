"""Planning time of APX (delta = 4) and the exact ILP (SCIP and HiGHS backends).

Instances: :func:`tether.recurrent.synthetic.exploration_instance`, about 200
vertices, 2,000 communication edges, 30 frontiers and 12 ready robots, as in
Sec. VII-A of Banfi et al. (the paper: up to 6 s for APX, 40 s for the ILP with
Gurobi). Measures per instance: APX time (median of repeats), ILP time per
backend, utilities, the optimality gap of APX, and the time of the shared
Dreyfus-Wagner DP over *all* subsets of at most 4 frontiers (no pruning).
ILP times are wall clock (``solve_time_s``) and process CPU time, which is
less sensitive to other jobs on a shared machine.

With ``--compare-src DIR`` (e.g. a ``git worktree`` of an older commit's
``src``), every instance is also measured with that code, in a subprocess run
right after the current code on the same instance, so that old and new are
timed under the same load; the JSON then holds both and their ratios.

Usage::

    python benchmarks/bench_planning.py [--instances 10] [--time-limit 120]
        [--compare-src /tmp/old/src] [--conditions "..."]

Writes ``benchmarks/results/planning.json``.
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

import numpy as np

from tether.recurrent import _problem
from tether.recurrent._apx import SharedSteiner
from tether.recurrent.configuration import optimal_configuration
from tether.recurrent.synthetic import exploration_instance


def machine_info() -> dict:
    from importlib.metadata import version

    from _machine import machine  # benchmarks/_machine.py (script directory)

    info = machine()
    for pkg in ("networkx", "highspy", "pyscipopt"):
        info[pkg] = version(pkg)
    return info


def full_dp_time(inst, delta: int = 4) -> tuple[float, int]:
    """Time of the shared DP over every subset of <= delta frontiers (no lazy top level)."""
    prob = _problem.build(inst.graph, inst.base, inst.utilities, inst.budget)
    fr = prob.frontiers[prob.dist[0, prob.frontiers] <= prob.budget]
    t = time.perf_counter()
    dp = SharedSteiner(prob.dist, fr, prob.budget, delta)
    dp.top_costs(np.flatnonzero(dp.alive[dp.delta]))
    return time.perf_counter() - t, sum(len(c) for c in dp.levels.combos.values())


def _flag(row: dict, backend: str) -> str:
    return "" if row[f"ilp_{backend}_proven_optimal"] else " (not proven)"


def measure(seed: int, time_limit: float, repeats: int) -> dict:
    """All measurements on ``exploration_instance(seed)`` with the importable code."""
    inst = exploration_instance(seed)
    g = inst.graph
    call = (g, inst.base, inst.utilities, inst.budget)
    optimal_configuration(*call, "apx", 4)  # warm caches (subset tables)
    apx_runs = [optimal_configuration(*call, "apx", 4) for _ in range(repeats)]
    apx = apx_runs[0]
    row = {
        "seed": seed,
        "vertices": g.number_of_nodes(),
        "edges": g.number_of_edges(),
        "frontiers": len(inst.utilities),
        "robots": inst.budget,
        "apx_time_s": statistics.median(c.solve_time_s for c in apx_runs),
        "apx_utility": apx.utility,
        "apx_vertices": sorted(int(v) for v in apx.vertices),
        "apx_proven_optimal": apx.proven_optimal,
    }
    row["dp_all_subsets_s"], row["dp_subsets"] = full_dp_time(inst)
    for backend in ("scip", "highs"):
        cpu = time.process_time()
        ilp = optimal_configuration(*call, "ilp", backend=backend, time_limit_s=time_limit)
        row[f"ilp_{backend}_cpu_s"] = time.process_time() - cpu
        row[f"ilp_{backend}_time_s"] = ilp.solve_time_s
        row[f"ilp_{backend}_utility"] = ilp.utility
        row[f"ilp_{backend}_proven_optimal"] = ilp.proven_optimal
        row[f"ilp_{backend}_upper_bound"] = ilp.upper_bound
    best = max(row["ilp_scip_utility"], row["ilp_highs_utility"])
    row["apx_gap"] = (best - apx.utility) / best if best > 0 else 0.0
    return row


def measure_elsewhere(src: Path, seed: int, time_limit: float, repeats: int) -> dict:
    """:func:`measure` with the ``tether`` found in ``src`` (a subprocess)."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(src), str(Path(__file__).parent)]))
    out = subprocess.run(
        [sys.executable, __file__, "--worker-seed", str(seed), "--time-limit", str(time_limit)]
        + ["--repeats", str(repeats)],
        env=env,
        check=True,
        capture_output=True,
        text=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


TIMES = (
    "apx_time_s",
    "dp_all_subsets_s",
    "ilp_scip_time_s",
    "ilp_scip_cpu_s",
    "ilp_highs_time_s",
    "ilp_highs_cpu_s",
)


def summarize(rows: list[dict]) -> dict:
    def stats(key: str) -> dict:
        vals = [r[key] for r in rows]
        return {"median": statistics.median(vals), "max": max(vals), "mean": statistics.fmean(vals)}

    return {
        "summary": {k: stats(k) for k in (*TIMES, "apx_gap")},
        "apx_optimal_count": sum(r["apx_gap"] <= 1e-9 for r in rows),
        "ilp_scip_proven_count": sum(r["ilp_scip_proven_optimal"] for r in rows),
        "ilp_highs_proven_count": sum(r["ilp_highs_proven_optimal"] for r in rows),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--instances", type=int, default=10)
    ap.add_argument("--time-limit", type=float, default=120.0)
    ap.add_argument("--repeats", type=int, default=5, help="APX repeats (median)")
    ap.add_argument("--out", type=Path, default=Path(__file__).parent / "results" / "planning.json")
    ap.add_argument("--compare-src", type=Path, help="src directory of the code to compare with")
    ap.add_argument("--conditions", default="", help="free text: load on the machine etc.")
    ap.add_argument("--worker-seed", type=int, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker_seed is not None:  # subprocess of --compare-src: one row as JSON
        print(json.dumps(measure(args.worker_seed, args.time_limit, args.repeats)))
        return
    load_start = os.getloadavg()
    rows, base_rows = [], []
    for seed in range(args.instances):
        row = measure(seed, args.time_limit, args.repeats)
        rows.append(row)
        print(
            f"seed {seed}: |V|={row['vertices']} |E|={row['edges']} |F|={row['frontiers']} "
            f"apx {row['apx_time_s'] * 1e3:.1f} ms (gap {row['apx_gap']:.2%}), "
            f"dp-all {row['dp_all_subsets_s'] * 1e3:.0f} ms/{row['dp_subsets']} subsets, "
            f"scip {row['ilp_scip_time_s']:.2f} s{_flag(row, 'scip')}, "
            f"highs {row['ilp_highs_time_s']:.2f} s{_flag(row, 'highs')}",
            flush=True,
        )
        if args.compare_src is not None:
            base = measure_elsewhere(args.compare_src, seed, args.time_limit, args.repeats)
            base_rows.append(base)
            row["baseline"] = base
            row["same_apx_configuration"] = base["apx_vertices"] == row["apx_vertices"]
            print(
                f"  baseline: apx {base['apx_time_s'] * 1e3:.1f} ms, "
                f"scip {base['ilp_scip_time_s']:.2f} s{_flag(base, 'scip')}, "
                f"highs {base['ilp_highs_time_s']:.2f} s{_flag(base, 'highs')}, "
                f"same APX configuration: {row['same_apx_configuration']}",
                flush=True,
            )

    out = {
        "benchmark": "recurrent planning: optimal configuration (Banfi et al. Sec. IV)",
        "command": " ".join(["python", *sys.argv]),
        "conditions": args.conditions,
        "load_average_1_5_15min": {"start": load_start, "end": os.getloadavg()},
        "machine": machine_info(),
        "settings": {"delta": 4, "time_limit_s": args.time_limit, "apx_repeats": args.repeats},
        **summarize(rows),
    }
    if base_rows:
        out["baseline"] = {"src": str(args.compare_src), **summarize(base_rows)}
        out["speedup_old_over_new"] = {
            k: {
                "median_ratio": statistics.median(
                    b[k] / max(r[k], 1e-12) for r, b in zip(rows, base_rows, strict=True)
                )
            }
            for k in TIMES
        }
        out["same_apx_configuration_count"] = sum(r["same_apx_configuration"] for r in rows)
    out["instances"] = rows
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(out, indent=2))
    print(json.dumps(out["summary"], indent=2))
    if base_rows:
        print(json.dumps(out["baseline"]["summary"], indent=2))
        print(json.dumps(out["speedup_old_over_new"], indent=2))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
