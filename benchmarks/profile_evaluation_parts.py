"""CPU time of the parts of one ``multi_target`` evaluation, each timed in isolation.

Runs a trial (default: the town, 35 robots, the whole trial) and, at every call of the
fused evaluation kernel (:func:`tether.continuous.kernels.evaluate_fiedler_kernel`,
pairs + clearance + weights + Laplacian + ``dsyevr``), first times on the same
arguments: the whole call; the call without the eigenpair (``evaluate_kernel`` with the
Laplacian); the same without obstacles (no clearance search, no obstacle factor);
the eigenpair alone (``fiedler_kernel`` on that Laplacian); the pair search alone.
Each variant gets its own copy of the clearance cache table (the search sees the
state the real call sees); then the real call runs, so the trial is unchanged.
Prints the CPU time per call of each, the number of calls and, per call, the
segments (pairs within ``Rs``), those whose cache entry was renewed (field test or tree
search) and those with a clearance below ``R'o``.

Usage::

    python benchmarks/profile_evaluation_parts.py [SCENARIO] [STEPS]
"""

from __future__ import annotations

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


def timed(label: str, f: Callable[[], Any]) -> Any:
    t = time.process_time()
    out = f()
    acc[label] = acc.get(label, 0.0) + time.process_time() - t
    return out


def main() -> None:
    scenario = sys.argv[1] if len(sys.argv) > 1 else "multi_target_town"
    steps = int(sys.argv[2]) if len(sys.argv) > 2 else 0
    import tether.continuous.kernels as k
    import tether.continuous.weights as cw
    from tether.continuous.pair_kernels import pairs_in_range

    k.warm_up()
    jit.set_enabled(True)
    plain, fused, no_obstacles = cw._kernels()
    calls = [0]
    counts = {"segments": 0, "searched (entry renewed)": 0, "clearance below R'o": 0}

    def parts(*a: Any) -> Any:
        table = a[10]
        q, radii, obstacle_args, cache_args = a[0], a[1:7], a[7:10], a[11:15]
        fresh = lambda: tuple(x.copy() for x in table)  # noqa: E731
        t = fresh()
        timed("whole call", lambda: fused(*a[:10], t, *a[11:]))
        t = fresh()
        out = timed("no eigenpair", lambda: plain(q, *radii, True, *obstacle_args, t, *cache_args))
        t = fresh()
        timed("no eigenpair, no obstacles",
              lambda: plain(q, *radii, True, False, *a[8:10], t, *cache_args))  # fmt: skip
        timed("eigenpair alone", lambda: k.fiedler_kernel(out[10], len(out[8]), *a[15:20]))
        timed("pair search alone", lambda: pairs_in_range(q, a[2]))
        calls[0] += 1
        a_before, b_before = table[2].copy(), table[3].copy()
        result = fused(*a)
        renewed = (a_before != table[2]).any(axis=1) | (b_before != table[3]).any(axis=1)
        counts["segments"] += len(result[0][8])
        counts["searched (entry renewed)"] += int(renewed.sum())
        counts["clearance below R'o"] += int(np.isfinite(result[0][3]).sum())
        return result

    cw._kernels = lambda: (plain, parts, no_obstacles)  # the profiled call in the weights' place
    sc = load_scenario(scenario)
    b = build(sc, sc.seed)
    simmod.simulate(b.world, b.sensor, b.strategy, b.initial, dt_s=sc.sim.dt_s,
                    max_steps=steps or sc.sim.max_steps, rng=b.rng,
                    collision_distance_m=sc.sim.collision_distance_m)  # fmt: skip
    print(f"{scenario}: {calls[0]} fused evaluations")
    for label, s in acc.items():
        print(f"{label:28s} {s / max(calls[0], 1) * 1e3:7.4f} ms per call")
    for label, c in counts.items():
        print(f"{label:28s} {c / max(calls[0], 1):7.1f} per call")


if __name__ == "__main__":
    main()
