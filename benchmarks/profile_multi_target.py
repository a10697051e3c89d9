"""CPU time per control step of the parts of a ``multi_target`` trial (no cProfile).

Wraps the strategy's main calls with ``time.process_time`` counters and runs one trial
(default: the town, 35 robots, 300 control steps, compiled kernels on). Prints the
median control step (CPU) and each part's CPU time per step, summed over the run (a
part called in several places, such as the path states, counts every call; the A*
plans of the start-up and of new targets are in ``roles.plan``). Works with older
trees too (``PYTHONPATH=/tmp/old/src``); parts a tree does not have are left out (a tree
that senses on a grid in one compiled call reports it as one part; ``path closest
points`` are all closest-point queries, those of the roles' update counted in ``path
states`` before).
Run two trees at the same time to compare them under the same load.

Usage::

    python benchmarks/profile_multi_target.py [SCENARIO] [on|off] [STEPS]
"""

from __future__ import annotations

import functools
import sys
import time
from collections.abc import Callable
from typing import Any

import numpy as np

from tether import jit
from tether import sim as simmod
from tether.config import load_scenario
from tether.runner import build

acc: dict[str, float] = {}


def wrap(obj: Any, name: str, label: str) -> None:
    """Count the CPU time of ``obj.name`` under ``label`` (if ``obj`` has it)."""
    f = getattr(obj, name, None) if obj is not None else None
    if f is None:
        return

    @functools.wraps(f)
    def timed(*a: Any, **k: Any) -> Any:
        t = time.process_time()
        try:
            return f(*a, **k)
        finally:
            acc[label] = acc.get(label, 0.0) + time.process_time() - t

    setattr(obj, name, timed)


def main() -> None:
    scenario = sys.argv[1] if len(sys.argv) > 1 else "multi_target_town"
    on = (sys.argv[2] if len(sys.argv) > 2 else "on") == "on"
    steps = int(sys.argv[3]) if len(sys.argv) > 3 else 300
    if on:
        from tether.continuous.kernels import warm_up

        warm_up()
    jit.set_enabled(on)
    import tether.comm as comm
    import tether.continuous.consensus as co
    import tether.continuous.election as el
    import tether.continuous.multi_target as mt
    import tether.continuous.roles as roles
    import tether.continuous.tracking as tr
    import tether.continuous.weights as cw
    import tether.sensing.robots as sr

    try:
        import tether.sensing.robots_kernels as rk
    except ImportError:  # a tree without it
        rk = None
    import tether.world.clearance as wc
    import tether.world.grid as wg

    parts: list[tuple[Any, str, str]] = [
        (mt.MultiTargetStrategy, "step", "step (strategy)"),
        (mt.MultiTargetStrategy, "_communicate", "  communicate"),
        (roles.RolePlanner, "update", "    roles.update"),
        (roles.RolePlanner, "plan", "      roles.plan (A*, B-spline)"),
        (el.Election, "round", "    election.round"),
        (co.EfficiencyConsensus, "round", "    consensus.round"),
        (comm.MessageLayer, "exchange", "      message exchange"),
        (tr.PathSet, "states", "    path states"),
        (tr.PathSet, "closest", "    path closest points (all calls)"),
        (mt, "integrate", "  integrate"),
        (mt.MultiTargetStrategy, "_evaluate", "    evaluate"),
        (cw, "_evaluate_kernel", "      weights kernel (fuse: +eigen)"),
        (cw.WeightedGraph, "fiedler", "      Fiedler (fuse: in the kernel)"),
        (mt.MultiTargetStrategy, "_force", "    connectivity force"),
        (mt, "traveling_forces", "    traveling forces"),
        (mt.MultiTargetStrategy, "_observe", "  observe"),
        (wc.ObstacleIndex, "nearest_min", "    least clearance"),
        (mt.MultiTargetStrategy, "_bookkeep", "  bookkeeping"),
        (mt.MultiTargetStrategy, "sense", "sense"),
        (sr, "sensed_pairs", "  sensed pairs"),
        (wg.OccupancyGrid, "segments_clear", "    line of sight"),
        (rk, "sense_grid_kernel", "  sensed pairs + line of sight (one call)"),
        (simmod, "team_metrics", "team metrics"),
        (simmod, "_graph_metrics", "  lambda2, components"),
    ]
    for obj, name, label in parts:
        wrap(obj, name, label)
    sc = load_scenario(scenario)
    sc.team.n_robots = 35
    built = build(sc, sc.seed)
    acc.clear()
    stamps: list[float] = []

    class Stamps:
        record: Callable[..., None] = staticmethod(lambda *a: stamps.append(time.process_time()))

    res = simmod.simulate(built.world, built.sensor, built.strategy, built.initial,
                          dt_s=sc.sim.dt_s, max_steps=steps, rng=built.rng,
                          collision_distance_m=sc.sim.collision_distance_m,
                          recorder=Stamps())  # fmt: skip
    per_step = np.diff(stamps)[1:]
    print(f"{scenario}, 35 robots, {steps} steps, kernels {'on' if on else 'off'}: median step "
          f"{np.median(per_step) * 1e3:.3f} ms CPU, mean {np.mean(per_step) * 1e3:.3f} ms, "
          f"{res.strategy_metrics.get('substeps')} sub-steps")  # fmt: skip
    for _, _, label in parts:
        if label in acc:
            print(f"{label:34s} {acc[label] / steps * 1e3:7.3f} ms/step")


if __name__ == "__main__":
    main()
