"""Paired, in-run timing of the fused connectivity evaluation: variants side by side.

A whole-trial benchmark cannot resolve a 10 % change on a shared 2-core machine (single
trials of the same code spread by 15-40 %), and an evaluation replayed out of its run
stays in the CPU's caches, which a real step does not (the obstacle search's data are
evicted by everything else a control step does). Here a ``multi_target`` (or
``connectivity``) trial runs as usual, and at every call of the fused evaluation kernel
each variant below is timed on the same arguments, in rotating order, each with its own
clearance cache table; the run itself uses its own call, so the trial is unchanged.
The per-call differences between two variants are paired: load that hits one call hits
its partner too.

Variants (``--compare``):

* ``lists``: the clearance search with candidate lists (the default table) against the
  same search without them (an empty list pool: every segment nearer than ``R'o`` is
  searched in the tree at every evaluation);
* ``solver``: the eigenpair by LAPACK ``dsyevr`` against the certified small solver
  (``fiedler_method: auto``), on every evaluation's Laplacian; also their status counts
  and the largest relative difference of lambda2;
* ``parts``: the whole call, without the eigenpair, without the eigenpair and obstacles,
  the pair search alone, and the eigenpair alone.

    python benchmarks/paired_evaluation.py [SCENARIO] [--compare lists|solver|parts]
        [--robots N] [--steps N] [--out benchmarks/results/paired_evaluation.json]

SCENARIO: a built-in name or a YAML file (e.g. ``scenarios/paper/continuous_fig9_town.yaml``
with ``--robots 35``). Prints mean and median microseconds per call per variant and
the paired differences; writes them with the machine to the JSON (a dict per
``--compare``, kept across runs).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from tether import jit
from tether import sim as simmod
from tether.config import load_scenario
from tether.runfolder import machine
from tether.runner import build

OUT = Path(__file__).parent / "results" / "paired_evaluation.json"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenario", nargs="?", default="multi_target_town")
    ap.add_argument("--compare", choices=["lists", "solver", "parts"], default="lists")
    ap.add_argument("--robots", type=int, default=35, help="0: the scenario's team size")
    ap.add_argument("--steps", type=int, default=0, help="0: the scenario's sim.max_steps")
    ap.add_argument("--out", type=Path, default=OUT)
    args = ap.parse_args()

    jit.set_enabled(True)
    import tether.continuous.kernels as kernels
    import tether.continuous.weights as cw
    from tether.continuous.pair_kernels import pairs_in_range
    from tether.world.clearance import ObstacleIndex

    kernels.warm_up()
    plain, fused, no_obstacles = cw._kernels()
    sc = load_scenario(args.scenario)
    if args.robots:
        sc.team.n_robots = args.robots
    b = build(sc, sc.seed)
    indices: dict[str, ObstacleIndex] = {}

    def state(label: str, list_slots: int = ObstacleIndex.LIST_SLOTS_PER_KEY) -> tuple:
        if label not in indices:
            index = ObstacleIndex.from_world(b.world)
            index.LIST_SLOTS_PER_KEY = list_slots
            indices[label] = index
        return indices[label].kernel_state(16 * 35)

    times: dict[str, list[float]] = {}
    extra: dict[str, Any] = {"small_status": [], "lambda2_rel_diff": []}
    calls = [0]

    def timed(label: str, f: Callable[[], Any]) -> Any:
        t = time.perf_counter()
        out = f()
        times.setdefault(label, []).append(time.perf_counter() - t)
        return out

    def with_table(label: str, a: tuple, slots: int = ObstacleIndex.LIST_SLOTS_PER_KEY) -> Any:
        points, tree, table, used, _ = state(label, slots)
        out = fused(*a[:8], points, tree, table, used, *a[12:])
        indices[label].kernel_added(out[0][-1])
        return out

    def variants(a: tuple) -> list[tuple[str, Callable[[], Any]]]:
        q, radii = a[0], a[1:7]
        if args.compare == "lists":
            return [("with lists", lambda: with_table("lists", a)),
                    ("without lists", lambda: with_table("no lists", a, 0))]  # fmt: skip
        if args.compare == "parts":

            def no_eigen() -> Any:
                points, tree, table, used, _ = state("no eigen")
                out = plain(q, *radii, True, a[7], points, tree, table, used, *a[12:15])
                indices["no eigen"].kernel_added(out[-1])
                return out

            def free() -> Any:
                n3 = no_obstacles(q.shape[1])
                return plain(q, *radii, True, False, *n3[:3], 0, a[12], n3[4], a[14])

            return [("whole call", lambda: with_table("whole", a)),
                    ("without the eigenpair", no_eigen),
                    ("without the eigenpair and obstacles", free),
                    ("pair search", lambda: pairs_in_range(q, a[2]))]  # fmt: skip
        return []

    def shadow(*a: Any) -> Any:
        out = fused(*a)
        calls[0] += 1
        todo = variants(a)
        if todo:
            r = calls[0] % len(todo)
            for label, f in todo[r:] + todo[:r]:
                timed(label, f)
        if args.compare in ("solver", "parts"):
            lap, m, guess = out[0][10], len(out[0][8]), a[15]
            order = (True, False) if calls[0] % 2 else (False, True)
            found = {}
            for lapack in order:
                label = "dsyevr" if lapack else "small solver"
                if args.compare == "parts" and not lapack:
                    continue
                found[lapack] = timed(label, lambda lapack=lapack: kernels.fiedler_kernel(
                    lap, m, guess, lapack, *a[17:20]))  # fmt: skip
            if args.compare == "solver":
                extra["small_status"].append(int(found[False][3]))
                if found[True][0] and found[False][0]:
                    lam = max(found[True][1], 1e-300)
                    extra["lambda2_rel_diff"].append(abs(found[False][1] - found[True][1]) / lam)
        return out

    cw._kernels = lambda: (plain, shadow, no_obstacles)
    start = time.perf_counter()
    simmod.simulate(b.world, b.sensor, b.strategy, b.initial, dt_s=sc.sim.dt_s,
                    max_steps=args.steps or sc.sim.max_steps, rng=b.rng,
                    collision_distance_m=sc.sim.collision_distance_m)  # fmt: skip
    result: dict[str, Any] = {"scenario": str(args.scenario), "robots": len(b.initial.positions),
                              "calls": calls[0], "wall_s": time.perf_counter() - start,
                              "load_1min": os.getloadavg()[0], "machine": machine(),
                              "us_per_call": {}}  # fmt: skip
    for label, v in times.items():
        us = np.array(v) * 1e6
        result["us_per_call"][label] = {"mean": float(us.mean()), "median": float(np.median(us))}
        print(f"{label:38s} {len(us)} calls, mean {us.mean():7.1f} us, median {np.median(us):7.1f}")
    labels = list(times)
    if len(labels) >= 2:
        d = (np.array(times[labels[0]]) - np.array(times[labels[1]])) * 1e6
        result["paired_difference_us"] = {"of": labels[:2], "mean": float(d.mean()),
                                          "median": float(np.median(d))}  # fmt: skip
        print(f"paired {labels[0]} - {labels[1]}: mean {d.mean():.1f} us, "
              f"median {np.median(d):.1f} us")  # fmt: skip
    if extra["small_status"]:
        s = np.array(extra["small_status"])
        result["small_status_counts"] = {int(x): int((s == x).sum()) for x in np.unique(s)}
        result["lambda2_max_rel_diff"] = float(max(extra["lambda2_rel_diff"]))
        print("small solver status counts", result["small_status_counts"],
              "largest relative lambda2 difference", result["lambda2_max_rel_diff"])  # fmt: skip
    saved = json.loads(args.out.read_text()) if args.out.exists() else {}
    saved[args.compare] = result
    args.out.write_text(json.dumps(saved, indent=2) + "\n")
    print(f"wrote {args.out}", file=sys.stderr)


if __name__ == "__main__":
    main()
