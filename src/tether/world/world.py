"""The space robots move in: dimension, bounds and obstacles."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from tether.world.grid import OccupancyGrid


@dataclass(eq=False)
class World:
    """A 2-D or 3-D workspace, free or with obstacles.

    Obstacles are held as an :class:`OccupancyGrid` (for fast clearance and
    line-of-sight queries through its distance field) together with a matching
    obstacle point set (the continuous-connectivity paper's representation).

    Parameters
    ----------
    dim
        2 or 3.
    bounds_m
        ``(2, dim)`` lower/upper corners, or ``None`` for unbounded free space.
    grid
        Occupancy grid, or ``None`` for no obstacles.
    obstacle_points
        ``(m, dim)`` obstacle points; defaults to the occupied cell centres.
    name
        A label for records and figures.
    """

    dim: int = 2
    bounds_m: np.ndarray | None = None
    grid: OccupancyGrid | None = None
    obstacle_points: np.ndarray | None = None
    name: str = "free"
    meta: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.dim not in (2, 3):
            raise ValueError("dim must be 2 or 3")
        if self.grid is not None:
            if self.grid.dim != self.dim:
                raise ValueError(f"grid is {self.grid.dim}-D but world is {self.dim}-D")
            if self.bounds_m is None:
                self.bounds_m = self.grid.bounds_m
            if self.obstacle_points is None:
                self.obstacle_points = self.grid.obstacle_points()
        if self.obstacle_points is None:
            self.obstacle_points = np.empty((0, self.dim))
        if self.bounds_m is not None:
            self.bounds_m = np.asarray(self.bounds_m, dtype=float).reshape(2, self.dim)

    @property
    def has_obstacles(self) -> bool:
        return self.grid is not None and self.grid.any_occupied

    def in_bounds(self, points: np.ndarray) -> np.ndarray:
        points = np.atleast_2d(points)
        if self.bounds_m is None:
            return np.ones(len(points), dtype=bool)
        return np.all((points >= self.bounds_m[0]) & (points <= self.bounds_m[1]), axis=1)

    def points_free(self, points: np.ndarray, clearance_m: float = 0.0) -> np.ndarray:
        """Boolean ``(k,)``: inside the bounds and at least ``clearance_m`` from obstacles."""
        points = np.atleast_2d(np.asarray(points, dtype=float))
        ok = self.in_bounds(points)
        if self.grid is not None:
            if clearance_m > 0:
                ok &= self.grid.clearance_m(points) >= clearance_m
            else:
                ok &= ~self.grid.is_occupied(points)
        return ok

    def segments_clear(self, a: np.ndarray, b: np.ndarray, clearance_m: float = 0.0) -> np.ndarray:
        """Boolean ``(k,)``: straight segments ``a[k] -> b[k]`` avoid obstacles."""
        a = np.atleast_2d(np.asarray(a, dtype=float))
        b = np.atleast_2d(np.asarray(b, dtype=float))
        if self.grid is None or len(a) == 0:
            return np.ones(len(a), dtype=bool)
        return self.grid.segments_clear(a, b, clearance_m)

    def clearance_m(self, points: np.ndarray) -> np.ndarray:
        """Distance to the nearest obstacle (``inf`` in free space)."""
        points = np.atleast_2d(np.asarray(points, dtype=float))
        if self.grid is None:
            return np.full(len(points), np.inf)
        return self.grid.clearance_m(points)
