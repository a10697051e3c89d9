"""The path layer: A* on 3-D grids and the town's plans, compiled against the reference.

* A* (:func:`tether.paths.astar.astar_grid`, octile heuristic) on 100 x 100 x 20
  town-like grids (box buildings on a street grid, about 20 % of the cells occupied):
  corner to corner and between random free cells. The compiled search is the
  reference's step for step (the same paths); the reference (``TETHER_JIT=0``) is timed
  on the same searches, in turns.
* ``plan_path`` + ``smooth_path`` of 20 random pairs in the paper's town (50 m x 70 m x
  10 m at 0.25 m, planning grid at ``Rgrid = 0.75 m``), compiled; how many came out as
  splines (the others fall back to the polyline).
"""

from __future__ import annotations

import statistics

import numpy as np

from suite.core import Line, cpu_clock, row
from suite.report import num, register_table

SHAPE = (100, 100, 20)


def town_like(rng: np.random.Generator) -> np.ndarray:
    """Free mask with box buildings of random footprint and height on a street grid."""
    occ = np.zeros(SHAPE, dtype=bool)
    nx, ny, nz = SHAPE
    for x0 in range(4, nx - 12, 16):
        for y0 in range(4, ny - 12, 16):
            for _ in range(2):
                if rng.random() < 0.1:
                    continue
                bx, by = x0 + rng.integers(0, 5), y0 + rng.integers(0, 5)
                w, d = rng.integers(5, 11, size=2)
                occ[bx : bx + w, by : by + d, : rng.integers(nz // 3, nz + 1)] = True
    return ~occ


def _searches(grids: int) -> list[tuple[np.ndarray, tuple, tuple, str]]:
    rng = np.random.default_rng(0)
    out = []
    for seed in range(grids):
        free = town_like(np.random.default_rng(seed))
        free[0, 0, 0] = free[-1, -1, 0] = True
        out.append((free, (0, 0, 0), (99, 99, 0), "corner to corner"))
        cells = np.argwhere(free)
        for _ in range(4):
            a, b = cells[rng.choice(len(cells), 2, replace=False)]
            out.append((free, tuple(a), tuple(b), "random free pairs"))
    return out


@row("paths", "A* on 3-D grids and the town's plans, compiled and reference")
def paths(quick: bool) -> dict:
    from tether import jit
    from tether.paths.astar import astar_grid, plan_path, planning_grid
    from tether.paths.bspline import smooth_path
    from tether.world import free_positions, make_scene

    times: dict[tuple[str, bool], list[float]] = {}
    searches = _searches(2 if quick else 6)
    with jit.using(True):
        t0 = cpu_clock()
        astar_grid(*searches[0][:3])
        warm = cpu_clock() - t0
    for free, a, b, case in searches:
        for compiled in (True, False):
            with jit.using(compiled):
                t0 = cpu_clock()
                astar_grid(free, a, b, heuristic="octile")
                times.setdefault((case, compiled), []).append(cpu_clock() - t0)
    lines = []
    for case in ("corner to corner", "random free pairs"):
        ours, ref = (1e3 * statistics.median(times[(case, c)]) for c in (True, False))
        lines.append(Line(f"A* on a 100 x 100 x 20 town-like grid, {case} (median)", "ms", ours,
                          peer="the reference search (TETHER_JIT=0)", peer_value=ref,
                          warmup_s=warm if case == "corner to corner" else None))  # fmt: skip
    world = make_scene("town", 0, resolution_m=0.25)
    plan_s, smooth_s, kinds = [], [], []
    with jit.using(True):
        plan = planning_grid(world, cell_m=0.75)
        ends = free_positions(world, 2 * (4 if quick else 20), np.random.default_rng(1),
                              clearance_m=1.0)  # fmt: skip
        for a, b in ends.reshape(-1, 2, 3):
            t0 = cpu_clock()
            wp = plan_path(world, a, b, cell_m=0.75, planning=plan)
            t1 = cpu_clock()
            if wp is None:
                continue
            path = smooth_path(wp, world, planning=plan)
            t2 = cpu_clock()
            plan_s.append(t1 - t0)
            smooth_s.append(t2 - t1)
            kinds.append(path.kind)
    splines = sum(k != "polyline" for k in kinds)
    lines.append(Line(f"plan_path in the town, {len(plan_s)} random pairs (median)", "ms",
                      1e3 * statistics.median(plan_s),
                      extra={"smooth_path_ms": 1e3 * statistics.median(smooth_s),
                             "splines": splines, "paths": len(kinds)}))  # fmt: skip
    detail = {f"{case} {'compiled' if c else 'reference'}": statistics.median(v)
              for (case, c), v in times.items()}  # fmt: skip
    return {"lines": lines, "details": {"astar_s": detail, "splines": splines,
                                        "paths": len(kinds)}}  # fmt: skip


@register_table("paths")
def table_paths(doc: dict) -> str:
    lines = doc["rows"].get("paths", {}).get("lines", [])
    out = ["| case | compiled (ms) | reference (ms) |", "| --- | ---: | ---: |"]
    for ln in lines:
        if ln["peer_value"] is not None:
            out.append(f"| {ln['label']} | {num(ln['ours'])} | {num(ln['peer_value'])} |")
        else:
            ex = ln["extra"]
            out.append(f"| {ln['label']}; then `smooth_path` {num(ex['smooth_path_ms'])} ms; "
                       f"{ex['splines']} of {ex['paths']} smoothed as splines | "
                       f"{num(ln['ours'])} | - |")  # fmt: skip
    return "\n".join(out)
