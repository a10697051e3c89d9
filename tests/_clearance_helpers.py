"""The clearance tests' worlds and oracle: random box worlds (20 x 20 (x 8) m at 0.5 m) and
the least distance from segments to points by brute force."""

from __future__ import annotations

import numpy as np

from tether.geometry import point_segment_distance
from tether.world.grid import OccupancyGrid
from tether.world.world import World


def box_world(rng: np.random.Generator, dim: int = 3, boxes: int = 6) -> World:
    """``boxes`` random axis-aligned boxes of 2-6 cells a side (grid-aligned faces: ties)."""
    shape = (40, 40, 16)[:dim]
    occ = np.zeros(shape, dtype=bool)
    for _ in range(boxes):
        lo = rng.integers(0, np.array(shape) - 6)
        size = rng.integers(2, 7, size=dim)
        occ[tuple(slice(a, a + s) for a, s in zip(lo, size, strict=True))] = True
    return World(dim=dim, grid=OccupancyGrid(occ, 0.5, np.zeros(dim)))


def brute(points: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Least distance from every segment ``a[k] -> b[k]`` to ``points``, one by one."""
    return np.array([
        point_segment_distance(points, np.repeat(a[k : k + 1], len(points), 0),
                               np.repeat(b[k : k + 1], len(points), 0)).min()
        for k in range(len(a))
    ])  # fmt: skip
