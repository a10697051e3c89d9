"""When each cell of an exploration map became known, as one array.

A replay needs the known map at every frame; storing one map per frame is
heavy, but knowledge only grows, so one integer per cell says it all: the first
frame at which the cell is known (:data:`NEVER` if it never is). The map at frame
``k`` is ``first_seen <= k``.

Source, in this order:

* ``known_map.npz`` in the run folder (``steps`` ``(T,)`` and ``known`` ``(T, nx, ny)``
  booleans, the base station's map at those steps), when a strategy writes it;
* otherwise an approximation from the recorded robot positions: the cells in
  line of sight within the sensing range of a robot at a recorded step (a
  360-degree sensor, so it can run ahead of a narrow field of view and lag
  between recorded steps). Pictures label it "seen (approx.)".
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from tether.viewing.runfolder import RunData
    from tether.world.grid import OccupancyGrid

NEVER = np.iinfo(np.int32).max


def first_seen_from_maps(
    frame_steps: np.ndarray, steps: np.ndarray, known: np.ndarray
) -> np.ndarray:
    """First frame index at which each cell is known, from maps recorded at ``steps``."""
    known = np.asarray(known, dtype=bool)
    first_step_idx = np.where(known.any(axis=0), np.argmax(known, axis=0), -1)
    out = np.full(known.shape[1:], NEVER, dtype=np.int32)
    seen = first_step_idx >= 0
    step_of_cell = np.asarray(steps)[first_step_idx[seen]]
    out[seen] = np.searchsorted(np.asarray(frame_steps), step_of_cell, side="left")
    return out


def first_seen_by_sight(grid: OccupancyGrid, positions_m: np.ndarray, range_m: float) -> np.ndarray:
    """Approximate first frame each cell of a 2-D ``grid`` is seen by a robot.

    ``positions_m`` is ``(T, n, 2)``. A cell is seen when a ray from a robot
    reaches it within ``range_m`` before passing through an occupied cell (the
    occupied cell that stops the ray is seen too: walls are mapped).
    """
    occ = grid.occupied
    res = grid.resolution_m
    radius = max(range_m / res, 1.0)
    n_rays = int(np.clip(np.ceil(2 * np.pi * radius * 1.5), 16, 4096))
    angles = np.linspace(0.0, 2 * np.pi, n_rays, endpoint=False)
    dirs = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    s = np.arange(0.0, radius + 1e-9, 0.5)
    offsets = dirs[:, None, :] * s[None, :, None]  # (rays, samples, 2) in cells
    shape = np.asarray(occ.shape)
    out = np.full(occ.shape, NEVER, dtype=np.int32)
    last: np.ndarray | None = None
    for k in range(positions_m.shape[0]):
        pos = positions_m[k]
        if last is not None and np.allclose(pos, last, equal_nan=True):
            continue
        last = pos
        for p in pos:
            if not np.all(np.isfinite(p)):
                continue
            c = (p[:2] - grid.origin_m[:2]) / res
            cells = np.floor(c + offsets).astype(np.int64)
            inside = np.all((cells >= 0) & (cells < shape), axis=2)
            blocked = np.ones(inside.shape, dtype=bool)
            ci = cells[inside]
            blocked[inside] = occ[ci[:, 0], ci[:, 1]]
            before = np.cumsum(blocked, axis=1) - blocked
            vis = (before == 0) & inside
            v = cells[vis]
            sel = out[v[:, 0], v[:, 1]] == NEVER
            out[v[sel, 0], v[sel, 1]] = k
    return out


def first_seen(run: RunData) -> tuple[np.ndarray | None, bool]:
    """``(first_seen, exact)`` for an exploration run with a 2-D grid, else ``(None, False)``."""
    grid = run.grid
    if grid is None or grid.dim != 2 or not run.is_exploration:
        return None, False
    file = Path(run.path) / "known_map.npz"
    if file.exists():
        with np.load(file) as z:
            if z["known"].shape[1:] == grid.occupied.shape:
                return first_seen_from_maps(run.frame_steps, z["steps"], z["known"]), True
    sensing = float(run.scenario.sensing.range_m) if run.scenario is not None else run.range_m
    return first_seen_by_sight(grid, run.positions_m, sensing), False
