"""What a run and a campaign cost: start-up, compilation, trials, sweeps, placement.

* ``kernels_compile``: ``python -m tether.kernel_cache`` with an empty numba cache
  (a temporary ``NUMBA_CACHE_DIR``): what the first run on a new install pays once.
* ``run_startup``: ``tether run silent_demo --no-figures`` (12 robots, 239 steps), the
  whole process as a user runs it; the first of four runs apart (file cache).
* ``multi_target_trial``: 35-robot town trials of ``multi_target`` in this process,
  recorded as ``tether run`` records them, after a short warm-up trial (compiled kernels
  loaded): whole Fig. 9 trials (configurations 0-2, ``continuous_fig9_town``) and the
  first 60 s of ``multi_target_town`` (start-up planning included); CPU per control
  step and simulated time over CPU time.
* ``build_reuse``: ``runner.build`` of the Fig. 9 town trials: the first build of a
  process (world, distance field, obstacle index) and the next ones, which reuse them.
* ``sweep``: the silent paper's d0 grid x 4 seeds at 300 steps, on 1 and 2 local worker
  processes (and a Dask ``LocalCluster`` of 2 if dask is installed); trials per minute
  (wall clock: the workers are separate processes), the tables checked equal.
* ``placement``: ``tether.team.random_connected`` of 100,000 robots (free 2-D, 8 m
  spacing, 2 m separation), checked connected and separated.
"""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from suite.core import ROOT, Line, command, cpu_clock, row
from suite.recurrent import run_process
from suite.report import num, register_table


@row("kernels_compile", "first use: numba compiles every kernel once", full_only=True)
def kernels_compile(quick: bool) -> dict:
    import sys

    with tempfile.TemporaryDirectory() as cache:
        wall, cpu = command([sys.executable, "-m", "tether.kernel_cache"],
                            env={"NUMBA_CACHE_DIR": cache, "TETHER_JIT": "1"})  # fmt: skip
    line = Line("compile every kernel (empty cache, once per install)", "s", cpu,
                extra={"wall_s": wall})  # fmt: skip
    return {"lines": [line]}


@row("run_startup", "a short run: tether run silent_demo, whole process")
def run_startup(quick: bool) -> dict:
    first = run_process("silent_demo")
    runs = [run_process("silent_demo") for _ in range(1 if quick else 3)]
    line = Line("tether run silent_demo --no-figures (239 steps), whole process (CPU)", "s",
                statistics.median(c for _, c in runs), warmup_s=first[1],
                extra={"wall_s": statistics.median(w for w, _ in runs)})  # fmt: skip
    return {"lines": [line]}


def _trial(scenario: str | Path, seed: int, steps: int | None = None) -> dict:
    from tether.config import load_scenario
    from tether.record import TrajectoryRecorder
    from tether.runner import build
    from tether.sim import simulate

    sc = load_scenario(scenario)
    sc.sweep = {}
    sc.team.n_robots = 35
    built = build(sc, seed)
    recorder = TrajectoryRecorder(every=sc.output.record_every)
    t0 = cpu_clock()
    res = simulate(built.world, built.sensor, built.strategy, built.initial,
                   dt_s=sc.sim.dt_s, max_steps=steps or sc.sim.max_steps, rng=built.rng,
                   collision_distance_m=sc.sim.collision_distance_m, recorder=recorder)  # fmt: skip
    cpu = cpu_clock() - t0
    return {"seed": seed, "steps": res.steps, "sim_time_s": res.sim_time_s, "cpu_s": cpu,
            "dt_s": sc.sim.dt_s}  # fmt: skip


FIG9_TOWN = ROOT / "src" / "tether" / "scenarios" / "paper" / "continuous_fig9_town.yaml"


@row("multi_target_trial", "multi_target: 35-robot town trials, CPU per control step")
def multi_target_trial(quick: bool) -> dict:
    from tether import jit

    with jit.using(True):
        t0 = cpu_clock()
        _trial("multi_target_town", 0, 5)
        warm = cpu_clock() - t0
        runs = range(1 if quick else 3)
        whole = [_trial(FIG9_TOWN, seed, 60 if quick else None) for seed in runs]
        start = [_trial("multi_target_town", 0, 60 if quick else 600) for _ in runs]

    def per_step(trials: list[dict]) -> float:
        return statistics.median(t["cpu_s"] / t["steps"] for t in trials)

    lines = [
        Line("Fig. 9 town trial, 35 robots, whole trial: CPU per control step (dt 0.1 s)", "ms",
             1e3 * per_step(whole), goal="<= 1 ms (100x simulated time)", goal_value=1.0,
             warmup_s=warm, extra={"simulated_over_cpu": whole[0]["dt_s"] / per_step(whole),
                                   "steps": [t["steps"] for t in whole]}),
        Line("multi_target_town, 35 robots, first 60 s (start-up planning included)", "ms",
             1e3 * per_step(start), extra={"simulated_over_cpu": start[0]["dt_s"] / per_step(start),
                                           "steps": start[0]["steps"]}),
    ]  # fmt: skip
    return {"lines": lines, "details": {"whole": whole, "start": start}}


@row("build_reuse", "a campaign's trials: the first build of a process, then reused")
def build_reuse(quick: bool) -> dict:
    from tether.config import load_scenario
    from tether.runner import build

    path = ROOT / "src" / "tether" / "scenarios" / "paper" / "continuous_fig9_town.yaml"
    sc = load_scenario(path)
    sc.sweep = {}
    cpu = []
    for seed in range(3 if quick else 6):
        t0 = cpu_clock()
        build(sc, seed)
        cpu.append(cpu_clock() - t0)
    line = Line("build of a Fig. 9 town trial, reusing the process's world", "s",
                statistics.median(cpu[1:]), warmup_s=cpu[0])  # fmt: skip
    return {"lines": [line]}


def _sweep_table(path: Path) -> dict:
    import pyarrow.parquet as pq

    timing = {"wall_time_s", "cpu_time_s", "planning_time_mean_s", "planning_time_max_s",
              "run_dir"}  # fmt: skip
    rows = pq.read_table(path).to_pylist()
    return {r["trial_id"]: {k: v for k, v in r.items() if k not in timing} for r in rows}


@row("sweep", "a campaign: trials per minute on 1 and 2 local workers (and Dask)")
def sweep(quick: bool) -> dict:
    import importlib.util

    from tether.config import load_scenario, scenario_from_dict
    from tether.experiments.sweep import run_sweep

    data = load_scenario("silent_paper").model_dump(mode="json")
    data["sim"]["max_steps"] = 60 if quick else 300
    scenario = scenario_from_dict(data, "silent_paper (benchmark)")
    setups = [("1 local worker", "processes", 1), ("2 local workers", "processes", 2)]
    if not quick and importlib.util.find_spec("distributed") is not None:
        setups.append(("Dask LocalCluster, 2 workers", "dask", 2))
    per, reference = [], None
    with tempfile.TemporaryDirectory() as tmp:
        warm_data = dict(data, sim=dict(data["sim"], max_steps=5))
        t0 = time.perf_counter()  # untimed by the rows: file caches, numba's cache load
        run_sweep(scenario_from_dict(warm_data, "silent_paper (warm-up)"), Path(tmp) / "warm",
                  seeds=1, executor="processes", workers=1, progress=lambda _msg: None)  # fmt: skip
        warm = time.perf_counter() - t0
        for name, executor, workers in setups:
            folder = Path(tmp) / f"{executor}-{workers}"
            t0 = time.perf_counter()
            out = run_sweep(scenario, folder, seeds=1 if quick else 4, executor=executor,
                            workers=workers, progress=lambda _msg: None)  # fmt: skip
            wall = time.perf_counter() - t0
            table = _sweep_table(out.table)
            reference = reference or table
            per.append({"setup": name, "trials": len(table), "wall_s": wall,
                        "trials_per_min": 60 * len(table) / wall,
                        "same_table": table == reference})  # fmt: skip
    if not all(p["same_table"] for p in per):
        raise AssertionError("the executors' tables differ")
    one = per[0]["trials_per_min"]
    lines = [
        Line(f"sweep, {p['trials']} short silent trials, {p['setup']} (trials/min, wall)",
             "/min", p["trials_per_min"], higher_is_better=True,
             peer="-" if k == 0 else "1 local worker", peer_value=None if k == 0 else one,
             warmup_s=warm if k == 0 else None)
        for k, p in enumerate(per)
    ]  # fmt: skip
    return {"lines": lines, "details": {"setups": per}}


@row("placement", "random connected placement of 100,000 robots")
def placement(quick: bool) -> dict:
    from scipy.spatial import cKDTree

    from tether.graph import is_connected, pairs_within
    from tether.team import random_connected
    from tether.world.world import World

    n = 10_000 if quick else 100_000
    random_connected(1000, World(dim=2), np.random.default_rng(0), 8.0, 2.0)
    t0 = cpu_clock()
    pos = random_connected(n, World(dim=2), np.random.default_rng(1), 8.0, 2.0)
    took = cpu_clock() - t0
    nearest, _ = cKDTree(pos).query(pos, k=2)
    if not (
        len(pos) == n and nearest[:, 1].min() >= 2.0 and is_connected(n, pairs_within(pos, 8.0))
    ):
        raise AssertionError("the placement is not a connected, separated team")
    return {"lines": [Line(f"random connected placement, {n:,} robots", "s", took,
                           goal="<= 30 s", goal_value=30.0)]}  # fmt: skip


@register_table("sweep")
def table_sweep(doc: dict) -> str:
    out = ["| executor | trials | wall (s) | trials per minute | speed-up | same table |",
           "| --- | ---: | ---: | ---: | ---: | --- |"]  # fmt: skip
    per = doc["rows"].get("sweep", {}).get("details", {}).get("setups", [])
    for p in per:
        speed = p["trials_per_min"] / per[0]["trials_per_min"]
        out.append(f"| {p['setup']} | {p['trials']} | {num(p['wall_s'])} | "
                   f"{num(p['trials_per_min'])} | {num(speed)}x | "
                   f"{'yes' if p['same_table'] else 'no'} |")  # fmt: skip
    return "\n".join(out)
