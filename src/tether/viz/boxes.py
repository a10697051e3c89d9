"""Occupancy grids as a few boxes, for 3-D drawing (browser replay, ROS markers).

A 3-D grid of a town holds millions of cells but only tens of buildings; a
greedy merge of occupied cells into axis-aligned boxes gives about one box per
building or wall segment (doors stay open). The grid is first coarsened (a
coarse cell is occupied when any of its cells is) to keep the work and the
number of boxes bounded.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from tether.world.grid import OccupancyGrid


def coarsen(occupied: np.ndarray, factor: int) -> np.ndarray:
    """Max-pool a boolean grid by an integer ``factor`` along every axis (padding with free)."""
    if factor <= 1:
        return occupied
    shape = [int(np.ceil(s / factor)) * factor for s in occupied.shape]
    padded = np.zeros(shape, dtype=bool)
    padded[tuple(slice(0, s) for s in occupied.shape)] = occupied
    split = []
    for s in shape:
        split += [s // factor, factor]
    return padded.reshape(split).any(axis=tuple(range(1, 2 * occupied.ndim, 2)))


def greedy_boxes(occupied: np.ndarray) -> np.ndarray:
    """Cover the occupied cells of a 3-D grid exactly with disjoint boxes.

    Returns ``(B, 6)`` integer ``[x0, y0, z0, x1, y1, z1]`` (upper bounds exclusive).
    Each box grows from the first uncovered cell in C order along z, then y, then x.
    """
    occ = np.array(occupied, dtype=bool, copy=True)
    nx, ny, nz = occ.shape
    flat = occ.ravel()
    boxes: list[tuple[int, int, int, int, int, int]] = []
    for idx in np.flatnonzero(flat):
        if not flat[idx]:
            continue
        x, y, z = np.unravel_index(idx, occ.shape)
        z1 = z + 1
        while z1 < nz and occ[x, y, z1]:
            z1 += 1
        y1 = y + 1
        while y1 < ny and occ[x, y1, z:z1].all():
            y1 += 1
        x1 = x + 1
        while x1 < nx and occ[x1, y:y1, z:z1].all():
            x1 += 1
        occ[x:x1, y:y1, z:z1] = False
        boxes.append((int(x), int(y), int(z), int(x1), int(y1), int(z1)))
    return np.asarray(boxes, dtype=np.int64).reshape(-1, 6)


def obstacle_boxes(
    grid: OccupancyGrid, *, max_boxes: int = 4000, max_cells: int = 4_000_000
) -> np.ndarray:
    """``(B, 6)`` boxes in metres ``[x0, y0, z0, x1, y1, z1]`` covering a 3-D grid's obstacles.

    The grid is coarsened by the smallest factor that keeps it under ``max_cells``
    cells and the result under ``max_boxes`` boxes (each doubling of the factor
    can only merge more).
    """
    occ = grid.occupied
    if occ.ndim != 3 or not occ.any():
        return np.zeros((0, 6))
    factor = max(1, int(np.ceil((occ.size / max_cells) ** (1 / 3))))
    while True:
        cells = greedy_boxes(coarsen(occ, factor))
        if len(cells) <= max_boxes or factor >= max(occ.shape):
            break
        factor *= 2
    res = grid.resolution_m * factor
    lo = grid.origin_m[None, :] + cells[:, :3] * res
    hi = grid.origin_m[None, :] + cells[:, 3:] * res
    hi = np.minimum(hi, grid.bounds_m[1][None, :])
    return np.hstack([lo, hi])
