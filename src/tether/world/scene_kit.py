"""Building blocks of procedural scenes: parameter checks, rasterising, the World of a grid.

Shared by :mod:`tether.world.scenes` (the simple scenes and :func:`make_scene`)
and :mod:`tether.world.procedural` (the town and office of the
continuous-connectivity paper).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy import ndimage

from tether.errors import ScenarioError
from tether.world.grid import MAX_CELLS, OccupancyGrid
from tether.world.world import World

# Sizes of the continuous-connectivity paper's environments (Sec. 4.1):
# "50m x 70m for both the empty space and the town, and about 10m x 15m for the office".
OUTDOOR_SIZE_M = (50.0, 70.0)
OFFICE_SIZE_M = (10.0, 15.0)


def check_positive(scene: str, name: str, value: Any) -> float:
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float))
        or not 0 < value < float("inf")
    ):
        raise ScenarioError(f"scene {scene!r}: {name}: must be a positive number (got {value!r})")
    return float(value)


def check_number(scene: str, name: str, value: Any, lo: float, hi: float) -> float:
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float))
        or not lo <= value <= hi
        or not np.isfinite(value)
    ):
        raise ScenarioError(
            f"scene {scene!r}: {name}: must be a number in [{lo}, {hi}] (got {value!r})"
        )
    return float(value)


def check_common(scene: str, dim: Any, point_spacing_m: Any, slice_height_m: Any) -> None:
    """Checks shared by the 3-D scenes that can also be sliced to 2-D."""
    if dim not in (2, 3) or isinstance(dim, bool):
        raise ScenarioError(f"scene {scene!r}: dim: must be 2 or 3 (got {dim!r})")
    if point_spacing_m is not None:
        check_positive(scene, "point_spacing_m", point_spacing_m)
    check_number(scene, "slice_height_m", slice_height_m, 0.0, float("inf"))


def check_range(scene: str, name: str, value: Any) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ScenarioError(
            f"scene {scene!r}: {name}: must be a pair [min, max] of numbers (got {value!r})"
        ) from None
    if not 0 < lo <= hi:
        raise ScenarioError(f"scene {scene!r}: {name}: need 0 < min <= max (got {value!r})")
    return lo, hi


def check_size(scene: str, name: str, value: Any, dim: int) -> np.ndarray:
    size = floats(value)
    if size is None or size.shape != (dim,) or not np.all(size > 0):
        raise ScenarioError(
            f"scene {scene!r}: {name}: must be {dim} positive numbers (got {value!r})"
        )
    return size


def floats(value: Any) -> np.ndarray | None:
    """``value`` as a float array, or ``None`` if it is not numeric (ragged, strings, ...)."""
    if isinstance(value, (str, bytes, dict)):
        return None
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return None
    return array if np.isfinite(array).all() else None


def cells_of(size_m: np.ndarray, resolution_m: float, scene: str = "scene") -> tuple[int, ...]:
    """Grid shape of a box ``size_m`` at ``resolution_m``; refused beyond ``MAX_CELLS`` cells."""
    with np.errstate(over="ignore"):  # a tiny resolution: inf cells, refused below
        cells = np.maximum(np.round(np.asarray(size_m, dtype=float) / resolution_m), 1)
        total = float(np.prod(cells))
    if not np.isfinite(cells).all() or total > MAX_CELLS:
        raise ScenarioError(
            f"scene {scene!r}: resolution_m: {resolution_m:g} m over {np.asarray(size_m).tolist()} "
            f"m gives {total:.3g} cells, more than {MAX_CELLS:,}; raise "
            "resolution_m or shrink the scene"
        )
    return tuple(int(n) for n in cells)


def raster_box(occupied: np.ndarray, resolution_m: float, lo: Sequence, hi: Sequence, value: bool):
    """Set the cells whose centres lie in the box ``[lo, hi)`` (origin at 0)."""
    index = []
    for axis, (a, b) in enumerate(zip(lo, hi, strict=True)):
        start = max(int(np.ceil(a / resolution_m - 0.5)), 0)
        stop = min(int(np.ceil(b / resolution_m - 0.5)), occupied.shape[axis])
        if stop <= start:
            return
        index.append(slice(start, stop))
    occupied[tuple(index)] = value


def fill_pockets(occupied: np.ndarray) -> np.ndarray:
    """Mark free cells not face-connected to the largest free region as occupied."""
    labels, count = ndimage.label(~occupied)
    if count <= 1:
        return occupied
    sizes = np.bincount(labels.ravel())
    sizes[0] = 0
    return occupied | (labels != int(np.argmax(sizes)))


def scene_world(
    occupied: np.ndarray,
    resolution_m: float,
    name: str,
    meta: dict[str, Any],
    *,
    dim: int,
    slice_height_m: float,
    point_spacing_m: float,
) -> World:
    """A 3-D scene as a World, or its horizontal slice at ``slice_height_m`` if ``dim == 2``."""
    if dim == 2:
        if slice_height_m >= occupied.shape[2] * resolution_m:
            raise ScenarioError(
                f"scene {name!r}: slice_height_m: must be below the scene height "
                f"{occupied.shape[2] * resolution_m} m (got {slice_height_m!r})"
            )
        iz = min(max(int(slice_height_m / resolution_m), 0), occupied.shape[2] - 1)
        occupied = fill_pockets(np.ascontiguousarray(occupied[:, :, iz]))
        meta = {**meta, "slice_height_m": slice_height_m}
    grid = OccupancyGrid(occupied, resolution_m, np.zeros(dim))
    points = grid.surface_points(point_spacing_m)
    return World(dim=dim, grid=grid, obstacle_points=points, name=name, meta=meta)
