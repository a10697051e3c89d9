"""A 2-D occupancy grid made coarser, or raised to a 3-D building (the ``map`` scene in 3-D).

* :func:`cells_spanning`: how many cells of a resolution cover a length, tolerant of
  floating point (``484 * 0.1`` m is 484 cells, not 485);
* :func:`coarsen`: cells of ``k`` times the size, occupied when any of their cells is;
* :func:`extrude`: every occupied cell becomes a wall from the floor (``z = 0``) to the
  ceiling (``height_m``); the grid's vertical extent *is* floor and ceiling, and points
  outside a grid count as occupied, so nothing (a robot, a planned path) passes above a
  wall or leaves the building through its roof.
"""

from __future__ import annotations

import math

import numpy as np

from tether.errors import ScenarioError
from tether.world.grid import MAX_CELLS, OccupancyGrid, cells_spanning

__all__ = ["cells_spanning", "coarsen", "extrude"]


def coarsen(grid: OccupancyGrid, cell_m: float, scene: str = "map") -> OccupancyGrid:
    """The grid with cells of ``cell_m`` (a whole multiple of its resolution): a coarse cell
    is occupied when any of its cells is, and cells beyond the grid's edge count as occupied.

    Raises
    ------
    ScenarioError
        ``cell_m`` is not a whole multiple of the grid's resolution.
    """
    factor = round(cell_m / grid.resolution_m)
    if factor < 1 or not math.isclose(factor * grid.resolution_m, cell_m, rel_tol=1e-6):
        raise ScenarioError(
            f"scene {scene!r}: cell_m: must be a whole multiple of the map's "
            f"{grid.resolution_m:g} m per cell, e.g. {2 * grid.resolution_m:g} or "
            f"{3 * grid.resolution_m:g} (got {cell_m!r})"
        )
    if factor == 1:
        return grid
    shape = [-(-n // factor) * factor for n in grid.shape]  # rounded up to whole blocks
    padded = np.ones(shape, dtype=bool)
    padded[tuple(slice(0, n) for n in grid.shape)] = grid.occupied
    blocks = padded.reshape(
        [v for n in shape for v in (n // factor, factor)]
    )  # (nx, k, ny, k[, nz, k])
    coarse = blocks.any(axis=tuple(range(1, 2 * grid.dim, 2)))
    return OccupancyGrid(coarse, factor * grid.resolution_m, grid.origin_m)


def extrude(grid: OccupancyGrid, height_m: float, scene: str = "map") -> OccupancyGrid:
    """A 3-D grid: ``grid``'s occupied cells as walls from ``z = 0`` to ``height_m``.

    The height is rounded up to whole cells (:func:`cells_spanning`); the grid's origin is
    ``(x0, y0, 0)``.

    Raises
    ------
    ScenarioError
        The 3-D grid would have more than :data:`~tether.world.grid.MAX_CELLS` cells.
    """
    if grid.dim != 2:
        raise ValueError("extrude needs a 2-D grid")
    layers = cells_spanning(height_m, grid.resolution_m)
    total = grid.occupied.size * layers
    if total > MAX_CELLS:
        raise ScenarioError(
            f"scene {scene!r}: cell_m: {grid.shape[0]} x {grid.shape[1]} cells of "
            f"{grid.resolution_m:g} m raised {layers} cells high give {total:,} cells, more "
            f"than {MAX_CELLS:,}; give a larger cell_m (e.g. 0.25) or a smaller map"
        )
    occupied = np.repeat(grid.occupied[:, :, None], layers, axis=2)
    return OccupancyGrid(occupied, grid.resolution_m, np.append(grid.origin_m, 0.0))
