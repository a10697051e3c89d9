"""Occupancy grids in 2-D and 3-D.

Convention: ``occupied[ix, iy]`` (2-D) or ``occupied[ix, iy, iz]`` (3-D); cell
``c`` covers ``origin_m + resolution_m * [c, c + 1)`` along each axis, so the
world point of a cell centre is ``origin_m + resolution_m * (c + 0.5)``. This
matches ROS map_server's ``origin`` (the lower-left corner of the map) once the
image rows are flipped (see :mod:`tether.world.maps`).

Points outside the grid are treated as occupied: robots cannot leave the map.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np
from scipy import ndimage

from tether.world.los import segment_free

#: the most cells a grid (a scene, a map image, rasterised points) may have: 50 million
#: cells are 50 MB as booleans and some 400 MB for each float layer derived from them
MAX_CELLS = 50_000_000


#: relative tolerance of :func:`cells_spanning` (floating-point error of a product)
CELL_TOLERANCE = 1e-9


def cells_spanning(length_m: float, resolution_m: float) -> int:
    """The fewest cells of ``resolution_m`` that cover ``length_m`` (at least 1).

    A length that is a whole number of cells up to floating-point error counts as that
    number: ``cells_spanning(484 * 0.1, 0.1) == 484`` although ``484 * 0.1 / 0.1`` is
    ``484.00000000000006``.
    """
    ratio = length_m / resolution_m
    nearest = round(ratio)
    if math.isclose(ratio, nearest, rel_tol=CELL_TOLERANCE, abs_tol=CELL_TOLERANCE):
        return max(int(nearest), 1)
    return max(math.ceil(ratio), 1)


@dataclass(eq=False)
class OccupancyGrid:
    """A boolean occupancy grid with metric placement.

    Parameters
    ----------
    occupied
        Boolean array, one axis per spatial dimension (x first).
    resolution_m
        Edge length of a (square/cubic) cell in metres.
    origin_m
        World coordinates of the corner of cell ``(0, 0[, 0])``.
    """

    occupied: np.ndarray
    resolution_m: float = 1.0
    origin_m: np.ndarray = field(default_factory=lambda: np.zeros(2))

    def __post_init__(self) -> None:
        self.occupied = np.asarray(self.occupied, dtype=bool)
        if self.occupied.ndim not in (2, 3):
            raise ValueError("occupancy grid must be 2-D or 3-D")
        if not self.resolution_m > 0:
            raise ValueError("resolution_m must be > 0")
        origin = np.zeros(self.occupied.ndim)
        given = np.asarray(self.origin_m, dtype=float).ravel()
        origin[: min(len(given), len(origin))] = given[: len(origin)]
        self.origin_m = origin

    @property
    def dim(self) -> int:
        return self.occupied.ndim

    @property
    def shape(self) -> tuple[int, ...]:
        return self.occupied.shape

    @property
    def size_m(self) -> np.ndarray:
        return np.asarray(self.shape, dtype=float) * self.resolution_m

    @property
    def bounds_m(self) -> np.ndarray:
        """``(2, dim)`` array: lower and upper corner in world coordinates."""
        return np.stack([self.origin_m, self.origin_m + self.size_m])

    def to_cell(self, points: np.ndarray) -> np.ndarray:
        """Integer cell indices ``(k, dim)`` of world points (may be out of range)."""
        points = np.atleast_2d(np.asarray(points, dtype=float))
        return np.floor((points - self.origin_m) / self.resolution_m).astype(np.intp)

    def to_world(self, cells: np.ndarray) -> np.ndarray:
        """World coordinates of cell centres."""
        cells = np.atleast_2d(np.asarray(cells))
        return self.origin_m + (cells + 0.5) * self.resolution_m

    def inside(self, cells: np.ndarray) -> np.ndarray:
        cells = np.atleast_2d(cells)
        return np.all((cells >= 0) & (cells < np.asarray(self.shape)), axis=1)

    def is_occupied(self, points: np.ndarray) -> np.ndarray:
        """Boolean ``(k,)``: point lies in an occupied cell or outside the grid."""
        cells = self.to_cell(points)
        ok = self.inside(cells)
        out = np.ones(len(cells), dtype=bool)
        out[ok] = self.occupied[tuple(cells[ok].T)]
        return out

    @cached_property
    def any_occupied(self) -> bool:
        """Some cell is occupied (computed once: a grid is not changed after it is made,
        as :attr:`distance_field_m` assumes too)."""
        return bool(self.occupied.any())

    @cached_property
    def distance_field_m(self) -> np.ndarray:
        """Euclidean distance (m) from each free cell centre to the nearest occupied cell.

        Computed once with ``scipy.ndimage.distance_transform_edt``; 0 inside
        obstacles. A grid with no obstacle gets ``inf`` everywhere.
        """
        if not self.occupied.any():
            return np.full(self.shape, np.inf)
        return ndimage.distance_transform_edt(~self.occupied) * self.resolution_m

    def clearance_m(self, points: np.ndarray) -> np.ndarray:
        """Distance (m) from points to the nearest obstacle cell (0 outside the grid).

        Accurate to about half a cell (distance between cell centres).
        """
        cells = self.to_cell(points)
        ok = self.inside(cells)
        out = np.zeros(len(cells))
        out[ok] = self.distance_field_m[tuple(cells[ok].T)]
        return out

    def segments_clear(self, a: np.ndarray, b: np.ndarray, clearance_m: float = 0.0) -> np.ndarray:
        """Boolean ``(k,)``: segment ``a[k] -> b[k]`` (metres) keeps ``clearance_m`` from obstacles.

        Line of sight by :func:`tether.world.los.segment_free` (samples every
        half cell): with ``clearance_m = 0`` every sample must lie in a free
        cell; otherwise in a cell whose centre is at least
        ``max(clearance_m, resolution / 2)`` from an occupied one. Points
        outside the grid block. No dependence on the number of obstacles.
        """
        a = np.atleast_2d(np.asarray(a, dtype=float))
        b = np.atleast_2d(np.asarray(b, dtype=float))
        mask = self.free_mask(clearance_m)
        to_cells = 1.0 / self.resolution_m
        # the distance field of the free cells, if made already, lets the kernel skip samples
        field = self.__dict__.get("distance_field_m") if not clearance_m > 0 else None
        if field is not None and not field.flags.c_contiguous:
            field = None
        return segment_free(mask, (a - self.origin_m) * to_cells, (b - self.origin_m) * to_cells,
                            field=field, field_to_cells=to_cells)  # fmt: skip

    def free_mask(self, clearance_m: float = 0.0) -> np.ndarray:
        """The mask :meth:`segments_clear` samples: free cells, or cells ``clearance_m`` clear.

        Made once per clearance and kept (a 3-D town grid has millions of cells: making
        it cost more than the line-of-sight test of a whole team). Like the distance
        field, it assumes ``occupied`` is not modified in place.
        """
        key = float(clearance_m) if clearance_m > 0 else 0.0
        masks = self.__dict__.setdefault("_free_masks", {})
        if key not in masks:
            if len(masks) >= 8:  # a few clearances in practice; never an unbounded cache
                masks.clear()
            if key > 0:
                masks[key] = self.distance_field_m >= max(key, 0.5 * self.resolution_m)
            else:
                masks[key] = ~self.occupied
        return masks[key]

    def surface_points(
        self, spacing_m: float | None = None, *, outside_is_free: bool = False
    ) -> np.ndarray:
        """Centres of occupied cells with a free face-neighbour, ``(m, dim)`` in world coordinates.

        ``outside_is_free`` counts cells beyond the grid as free (then the
        grid's outer occupied layer is surface too). For any free point, the
        nearest occupied cell centre is a surface cell (an interior cell always
        has a closer occupied neighbour towards the point), so the surface
        replaces all occupied centres in clearance queries. With ``spacing_m``
        above the resolution, the surface is thinned to one cell per block of
        ``round(spacing_m / resolution_m)`` cells along each axis (a voxel-grid
        filter, about ``area / spacing_m**(dim-1)`` points). Every returned
        point is a cell centre inside an occupied cell.
        """
        occupied = self.occupied
        inner = ndimage.binary_erosion(occupied, border_value=0 if outside_is_free else 1)
        cells = np.argwhere(occupied & ~inner)
        stride = 1 if spacing_m is None else max(int(round(spacing_m / self.resolution_m)), 1)
        if stride > 1 and len(cells):
            _, keep = np.unique(cells // stride, axis=0, return_index=True)
            cells = cells[np.sort(keep)]
        return self.to_world(cells).reshape(-1, self.dim)

    def obstacle_points(self) -> np.ndarray:
        """Centres of occupied cells, ``(m, dim)`` in world coordinates."""
        return self.to_world(np.argwhere(self.occupied)).reshape(-1, self.dim)

    @classmethod
    def from_points(
        cls,
        points: np.ndarray,
        bounds_m: np.ndarray,
        resolution_m: float,
    ) -> OccupancyGrid:
        """Rasterise an obstacle point set into a grid covering ``bounds_m`` (``(2, dim)``)."""
        bounds_m = np.asarray(bounds_m, dtype=float)
        with np.errstate(over="ignore"):
            ratio = (bounds_m[1] - bounds_m[0]) / resolution_m
        if not np.isfinite(ratio).all() or float(np.prod(np.maximum(ratio, 1))) > MAX_CELLS:
            extent = np.maximum(np.ceil(ratio), 1)
        else:  # whole cells up to floating-point error: 484 * 0.1 m is 484 cells, not 485
            extent = np.array([cells_spanning(float(s), resolution_m) for s in
                               bounds_m[1] - bounds_m[0]], dtype=float)  # fmt: skip
        if not np.isfinite(extent).all() or float(np.prod(extent)) > MAX_CELLS:
            raise ValueError(
                f"a grid of {' x '.join(f'{e:.3g}' for e in extent)} cells is more than "
                f"{MAX_CELLS:,}; raise resolution_m or shrink the bounds"
            )
        shape = extent.astype(int)
        occ = np.zeros(tuple(shape), dtype=bool)
        grid = cls(occ, resolution_m, bounds_m[0])
        points = np.asarray(points, dtype=float).reshape(-1, len(shape))
        if len(points):
            cells = grid.to_cell(points)
            cells = cells[grid.inside(cells)]
            occ[tuple(cells.T)] = True
        return grid
