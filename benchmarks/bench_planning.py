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

With ``--sim-map`` (e.g. ``../shared/maps/grass.png``), the exploration
simulator is also run (12 robots, theta = 12, APX) and every planning
instance with at least ``--sim-min-frontiers`` frontiers it produces is
recorded and timed with APX again (and with the ``--compare-src`` code): the
simulator's late-mission graphs have many more frontiers than the synthetic
ones.

Usage::

    python benchmarks/bench_planning.py [--instances 10] [--time-limit 120]
        [--compare-src /tmp/old/src] [--conditions "..."]
        [--sim-map ../shared/maps/grass.png --sim-steps 900]

Writes ``benchmarks/results/planning.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import pickle
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from tether.recurrent.planning import problem as _problem
from tether.recurrent.planning.apx import SharedSteiner
from tether.recurrent.planning.configuration import optimal_configuration
from tether.recurrent.planning.synthetic import exploration_instance


def machine_info() -> dict:
    from importlib.metadata import version

    from _machine import machine  # benchmarks/_machine.py (script directory)

    info = machine()
    for pkg in ("networkx", "highspy", "pyscipopt"):
        info[pkg] = version(pkg)
    return info


def record_sim_instances(map_path: Path, seed: int, steps: int, min_frontiers: int) -> list:
    """Planning instances of one simulated mission (theta = 12, APX) with many frontiers.

    Records the arguments of every ``optimal_configuration`` call the
    strategy makes (by wrapping the name it imported) whose utilities hold at
    least ``min_frontiers`` frontiers.
    """
    import tether.recurrent.replanning as replanning
    from tether.recurrent.exploration.sim import ExplorationConfig, ExplorationSim, random_base
    from tether.world.maps import load_map

    recorded = []
    solve = replanning.optimal_configuration

    def recording(graph, base, utilities, budget, *args, **kwargs):
        if len(utilities) >= min_frontiers:
            fixed = frozenset(kwargs.get("fixed", ()))
            recorded.append((graph.copy(), base, dict(utilities), budget, fixed))
        return solve(graph, base, utilities, budget, *args, **kwargs)

    occupied = load_map(map_path, occupied_thresh=0.999, free_thresh=0.998).occupied
    cfg = ExplorationConfig(n_robots=12, steps=steps)
    base = random_base(occupied, cfg.coarse_factor, np.random.default_rng(seed))
    strategy = replanning.RecurrentStrategy(theta=12, method="apx", delta=4)
    replanning.optimal_configuration = recording
    try:
        sim = ExplorationSim(occupied, base, strategy, cfg)
        strategy.start(sim)
        for _ in range(steps):
            sim.step()
    finally:
        replanning.optimal_configuration = solve
    return recorded


def time_sim_instances(recorded: list) -> list[dict]:
    """APX (delta = 4) time, utility and configuration on recorded instances."""
    rows = []
    for graph, base, utilities, budget, fixed in recorded:
        conf = optimal_configuration(graph, base, utilities, budget, "apx", 4, fixed=fixed)
        rows.append(
            {
                "vertices": graph.number_of_nodes(),
                "edges": graph.number_of_edges(),
                "frontiers": len(utilities),
                "robots": budget,
                "busy": len(fixed),
                "apx_time_s": conf.solve_time_s,
                "apx_utility": conf.utility,
                "apx_vertices": sorted(repr(v) for v in conf.vertices),
            }
        )
    return rows


def sim_benchmark(args: argparse.Namespace) -> dict:
    """The ``--sim-map`` part: record, time, and time with the ``--compare-src`` code."""
    recorded = record_sim_instances(
        args.sim_map, args.sim_seed, args.sim_steps, args.sim_min_frontiers
    )
    rows = time_sim_instances(recorded)
    out = {
        "map": str(args.sim_map),
        "seed": args.sim_seed,
        "steps": args.sim_steps,
        "min_frontiers": args.sim_min_frontiers,
        "instances": rows,
    }
    if args.compare_src is not None and recorded:
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "recorded.pkl"
            path.write_bytes(pickle.dumps(recorded))
            base = run_elsewhere(args.compare_src, ["--worker-sim", str(path)])
        for row, old in zip(rows, base, strict=True):
            row["baseline_apx_time_s"] = old["apx_time_s"]
            row["same_apx_configuration"] = old["apx_vertices"] == row["apx_vertices"]
    if rows:
        times = [r["apx_time_s"] for r in rows]
        out["apx_time_s"] = {"median": statistics.median(times), "max": max(times)}
        if "baseline_apx_time_s" in rows[0]:
            old = [r["baseline_apx_time_s"] for r in rows]
            out["baseline_apx_time_s"] = {"median": statistics.median(old), "max": max(old)}
            out["same_apx_configuration_count"] = sum(r["same_apx_configuration"] for r in rows)
    return out


def full_dp_time(inst, delta: int = 4) -> tuple[float, int]:
    """Time of the shared DP over every subset of <= delta frontiers (no lazy top level).

    A first untimed run builds the subset tables (cached per frontier count).
    """
    prob = _problem.build(inst.graph, inst.base, inst.utilities, inst.budget)
    fr = prob.frontiers[prob.dist[0, prob.frontiers] <= prob.budget]
    SharedSteiner(prob.dist, fr, prob.budget, delta)
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


def run_elsewhere(src: Path, worker_args: list[str]) -> object:
    """Run this script as a worker with the ``tether`` found in ``src``; its JSON output."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(src), str(Path(__file__).parent)]))
    out = subprocess.run(
        [sys.executable, __file__, *worker_args],
        env=env,
        check=True,
        capture_output=True,
        text=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def measure_elsewhere(src: Path, seed: int, time_limit: float, repeats: int) -> dict:
    """:func:`measure` with the ``tether`` found in ``src`` (a subprocess)."""
    worker = ["--worker-seed", str(seed), "--time-limit", str(time_limit)]
    return run_elsewhere(src, [*worker, "--repeats", str(repeats)])


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
    ap.add_argument("--sim-map", type=Path, help="occupancy map for the simulator instances")
    ap.add_argument("--sim-seed", type=int, default=0)
    ap.add_argument("--sim-steps", type=int, default=900)
    ap.add_argument("--sim-min-frontiers", type=int, default=60)
    ap.add_argument("--worker-seed", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--worker-sim", type=Path, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker_seed is not None:  # subprocess of --compare-src: one row as JSON
        print(json.dumps(measure(args.worker_seed, args.time_limit, args.repeats)))
        return
    if args.worker_sim is not None:  # subprocess of --compare-src: simulator instances
        print(json.dumps(time_sim_instances(pickle.loads(args.worker_sim.read_bytes()))))
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
    if args.sim_map is not None:
        out["simulator"] = sim_benchmark(args)
        sim = {k: v for k, v in out["simulator"].items() if k != "instances"}
        print(json.dumps(sim, indent=2))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(out, indent=2))
    print(json.dumps(out["summary"], indent=2))
    if base_rows:
        print(json.dumps(out["baseline"]["summary"], indent=2))
        print(json.dumps(out["speedup_old_over_new"], indent=2))
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
