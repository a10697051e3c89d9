"""Time of the path layer (continuous-connectivity paper, Sec. 3.2): A*, planning, smoothing.

Measures, on one machine (recorded with :func:`tether.runfolder.machine`):

* ``astar_town_like``: :func:`tether.paths.astar.astar_grid` on 100 x 100 x 20 grids with
  random box buildings on a street grid (about 20 % of the cells, 30 % of the ground layer),
  corner to corner and between random free cells, octile and Euclidean heuristics;
* ``astar_adversarial``: the same grid cut by a wall with one hole in the far corner
  (A* has to close most free cells: the worst case), and an unreachable goal (answered
  by the component pre-check);
* ``town``: the paper's town scene (50 m x 70 m x 10 m, 0.25 m cells): the planning grid
  at ``Rgrid = 0.75 m`` (distance field included on the first call), ``plan_path``,
  ``smooth_path``, ``closest_point`` and ``virtual_state`` between random free points.

Each is timed with the compiled A* (``paths/astar_kernels.py``) and with the Python
reference in the same run (``--kernels both``, the default; ``on`` or ``off`` for one),
after a warm-up that loads the kernel from numba's cache.

Usage: python benchmarks/bench_paths.py [--repeats 5] [--kernels both|on|off]
       [--out benchmarks/results/paths.json]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from pathlib import Path

import numpy as np

from tether import jit
from tether.paths.astar import astar_grid, plan_path, planning_grid
from tether.paths.bspline import closest_point, smooth_path
from tether.paths.virtual_point import virtual_state
from tether.runfolder import machine
from tether.world import free_positions, make_scene

SHAPE = (100, 100, 20)


def town_like(rng: np.random.Generator, shape=SHAPE) -> np.ndarray:
    """Free mask with box buildings of random footprint and height on a street grid."""
    occ = np.zeros(shape, dtype=bool)
    nx, ny, nz = shape
    for x0 in range(4, nx - 12, 16):
        for y0 in range(4, ny - 12, 16):
            for _ in range(2):
                if rng.random() < 0.1:
                    continue
                bx, by = x0 + rng.integers(0, 5), y0 + rng.integers(0, 5)
                w, d = rng.integers(5, 11, size=2)
                occ[bx : bx + w, by : by + d, : rng.integers(nz // 3, nz + 1)] = True
    return ~occ


CPU_S: list[float] = []  # process CPU time of every timed() call, in order


def timed(fn, *args, **kwargs):
    """``(result, wall seconds)``; the process CPU seconds are appended to ``CPU_S``."""
    c0, t0 = time.process_time(), time.perf_counter()
    out = fn(*args, **kwargs)
    wall = time.perf_counter() - t0
    CPU_S.append(time.process_time() - c0)
    return out, wall


def summary_ms(times_s: list[float], cpu_s: list[float] | None = None) -> dict[str, float]:
    """Wall-clock statistics in ms, and the median CPU time when given (less load-sensitive)."""
    ms = [1e3 * t for t in times_s]
    out = {"n": len(ms), "median_ms": statistics.median(ms), "max_ms": max(ms), "min_ms": min(ms)}
    if cpu_s:
        out["cpu_median_ms"] = 1e3 * statistics.median(cpu_s)
    return out


def bench_astar(repeats: int) -> dict:
    out: dict = {"shape": list(SHAPE)}
    rng = np.random.default_rng(0)
    for heuristic in ("octile", "euclidean"):
        corner, random_pairs, lengths, cpu_corner, cpu_random = [], [], [], [], []
        for seed in range(repeats):
            free = town_like(np.random.default_rng(seed))
            free[0, 0, 0] = free[-1, -1, 0] = True
            path, dt = timed(astar_grid, free, (0, 0, 0), (99, 99, 0), heuristic=heuristic)
            corner.append(dt)
            cpu_corner.append(CPU_S[-1])
            lengths.append(len(path))
            cells = np.argwhere(free)
            for _ in range(4):
                a, b = cells[rng.choice(len(cells), 2, replace=False)]
                random_pairs.append(timed(astar_grid, free, a, b, heuristic=heuristic)[1])
                cpu_random.append(CPU_S[-1])
        out[heuristic] = {
            "corner_to_corner": summary_ms(corner, cpu_corner),
            "random_pairs": summary_ms(random_pairs, cpu_random),
            "corner_path_cells": lengths,
        }
    free = town_like(np.random.default_rng(0))
    out["occupied_fraction"] = float(1.0 - free.mean())
    wall = free.copy()
    wall[:, 50, :] = False
    _, unreachable = timed(astar_grid, wall, (0, 0, 0), (0, 99, 0))
    wall[99, 50, 19] = True
    n_hard = max(repeats // 2, 1)
    hard = [timed(astar_grid, wall, (0, 0, 0), (0, 99, 0))[1] for _ in range(n_hard)]
    out["adversarial_wall_one_hole"] = summary_ms(hard, CPU_S[-n_hard:])
    out["adversarial_free_cells"] = int(wall.sum())
    out["unreachable_ms"] = 1e3 * unreachable
    return out


def bench_town(n_pairs: int) -> dict:
    world = make_scene("town", 0, resolution_m=0.25)
    cell = 0.75  # Table 2, Rgrid outdoor
    plan, first = timed(planning_grid, world, cell_m=cell)  # includes the distance field
    _, again = timed(planning_grid, world, cell_m=cell)
    rng = np.random.default_rng(1)
    ends = free_positions(world, 2 * n_pairs, rng, clearance_m=1.0)
    t_plan, t_smooth, t_closest, t_virtual, kinds, lengths = [], [], [], [], [], []
    cpu_plan: list[float] = []
    cpu_smooth: list[float] = []
    for a, b in ends.reshape(n_pairs, 2, 3):
        wp, dt = timed(plan_path, world, a, b, cell_m=cell, planning=plan)
        if wp is None:
            continue
        t_plan.append(dt)
        cpu_plan.append(CPU_S[-1])
        path, dt = timed(smooth_path, wp, world, planning=plan)
        t_smooth.append(dt)
        cpu_smooth.append(CPU_S[-1])
        kinds.append(path.kind)
        lengths.append(path.length_m)
        q = path.point(0.4 * path.length_m) + 0.5
        cp, dt = timed(closest_point, path, q)
        t_closest.append(dt)
        t_virtual.append(timed(virtual_state, path, cp.s_m, 3.0)[1])
    return {
        "grid_shape": list(world.grid.shape),
        "planning_shape": list(plan.shape),
        "planning_occupied_fraction": float(plan.occupied.mean()),
        "planning_grid_first_ms": 1e3 * first,
        "planning_grid_cached_df_ms": 1e3 * again,
        "plan_path": summary_ms(t_plan, cpu_plan),
        "smooth_path": summary_ms(t_smooth, cpu_smooth),
        "closest_point": summary_ms(t_closest),
        "virtual_state": summary_ms(t_virtual),
        "smoothed_kinds": {k: kinds.count(k) for k in sorted(set(kinds))},
        "path_length_m": {"median": statistics.median(lengths), "max": max(lengths)},
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--pairs", type=int, default=20)
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results/paths.json")
    parser.add_argument("--kernels", choices=("both", "on", "off"), default="both")
    args = parser.parse_args()
    load_before = os.getloadavg()
    result: dict = {"machine": machine()}
    modes = {"both": ("off", "on"), "on": ("on",), "off": ("off",)}[args.kernels]
    if "on" in modes:
        from tether.paths.astar_kernels import warm_up

        warm_up()
    for mode in modes:
        with jit.using(mode == "on"):
            name = "compiled" if mode == "on" else "reference"
            result[name] = {"astar_town_like": bench_astar(args.repeats),
                            "town": bench_town(args.pairs)}  # fmt: skip
    # other jobs on the machine slow the pure-Python search: record the load around it
    result["load_average_1min_before_after"] = [load_before[0], os.getloadavg()[0]]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2) + "\n")
    for name in ("reference", "compiled"):
        if name in result:
            print(f"== {name} A*")
            report(result[name])
    print(f"wrote {args.out}")


def report(result: dict) -> None:
    """Print one mode's numbers."""
    a = result["astar_town_like"]
    t = result["town"]
    print(f"A* {SHAPE} town-like, occupied {a['occupied_fraction']:.0%}:")
    for h in ("octile", "euclidean"):
        c, r = a[h]["corner_to_corner"], a[h]["random_pairs"]
        print(
            f"  {h:9s} corner-to-corner median {c['median_ms']:.0f} ms (max {c['max_ms']:.0f},"
            f" CPU {c['cpu_median_ms']:.1f}), random pairs median {r['median_ms']:.1f} ms"
            f" (max {r['max_ms']:.0f}, CPU {r['cpu_median_ms']:.1f})"
        )
    hard = a["adversarial_wall_one_hole"]
    print(
        f"  adversarial (wall, one hole; {a['adversarial_free_cells']} free cells):"
        f" median {hard['median_ms']:.0f} ms (CPU {hard['cpu_median_ms']:.0f});"
        f" unreachable: {a['unreachable_ms']:.1f} ms"
    )
    print(f"town {t['grid_shape']} -> planning grid {t['planning_shape']} at Rgrid 0.75 m:")
    print(
        f"  planning grid {t['planning_grid_first_ms']:.0f} ms first"
        f" (distance field), {t['planning_grid_cached_df_ms']:.0f} ms after"
    )
    for key in ("plan_path", "smooth_path", "closest_point", "virtual_state"):
        print(f"  {key:14s} median {t[key]['median_ms']:.2f} ms, max {t[key]['max_ms']:.2f} ms")
    print(f"  smoothed: {t['smoothed_kinds']}")


if __name__ == "__main__":
    main()
