"""Procedural, seeded scenes, registered by name in :data:`tether.registry.SCENES`.

Every scene is a function ``(rng, **params) -> World``; all randomness comes
from ``rng`` so a scene is fully determined by its seed and parameters.

=============== ===== =======================================================
name            dim   what
=============== ===== =======================================================
``free``        2/3   no obstacles, optional bounds
``empty``       3     obstacle-free 50 m x 70 m box (continuous paper, Sec. 4)
``town``        3     50 m x 70 m of streets and box buildings (Sec. 4, Fig. 7)
``office``      3     about 10 m x 15 m: rooms along a corridor, with doors (Fig. 8)
``map``         2     a PNG/PGM or ROS YAML map file (:func:`~tether.world.maps.load_map`)
``user_points`` 2/3   obstacle points from a ``.npy``/``.csv``/``.xyz`` file
=============== ===== =======================================================

The 3-D scenes come with a 3-D :class:`~tether.world.grid.OccupancyGrid` and a
matching obstacle point set (the paper's set ``O`` of obstacle points, Sec. 2):
centres of occupied cells on obstacle *surfaces*, thinned to about one point
per ``point_spacing_m``, so every point lies in an occupied cell.
"""

from __future__ import annotations

import inspect
from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy import ndimage

from tether.errors import MapError, ScenarioError
from tether.registry import SCENES
from tether.world.grid import OccupancyGrid
from tether.world.maps import load_map, load_points
from tether.world.world import World

__all__ = [
    "empty",
    "free",
    "free_positions",
    "make_scene",
    "map_scene",
    "office",
    "surface_points",
    "town",
    "user_points",
]

# Sizes of the continuous-connectivity paper's environments (Sec. 4.1):
# "50m x 70m for both the empty space and the town, and about 10m x 15m for the office".
OUTDOOR_SIZE_M = (50.0, 70.0)
OFFICE_SIZE_M = (10.0, 15.0)


# --------------------------------------------------------------------------- helpers


def _check_positive(scene: str, name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
        raise ScenarioError(f"scene {scene!r}: {name}: must be a positive number (got {value!r})")
    return float(value)


def _check_number(scene: str, name: str, value: Any, lo: float, hi: float) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not lo <= value <= hi:
        raise ScenarioError(
            f"scene {scene!r}: {name}: must be a number in [{lo}, {hi}] (got {value!r})"
        )
    return float(value)


def _check_common(scene: str, dim: Any, point_spacing_m: Any, slice_height_m: Any) -> None:
    """Checks shared by the 3-D scenes that can also be sliced to 2-D."""
    if dim not in (2, 3) or isinstance(dim, bool):
        raise ScenarioError(f"scene {scene!r}: dim: must be 2 or 3 (got {dim!r})")
    if point_spacing_m is not None:
        _check_positive(scene, "point_spacing_m", point_spacing_m)
    _check_number(scene, "slice_height_m", slice_height_m, 0.0, float("inf"))


def _check_range(scene: str, name: str, value: Any) -> tuple[float, float]:
    try:
        lo, hi = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ScenarioError(
            f"scene {scene!r}: {name}: must be a pair [min, max] of numbers (got {value!r})"
        ) from None
    if not 0 < lo <= hi:
        raise ScenarioError(f"scene {scene!r}: {name}: need 0 < min <= max (got {value!r})")
    return lo, hi


def _check_size(scene: str, name: str, value: Any, dim: int) -> np.ndarray:
    size = _floats(value)
    if size is None or size.shape != (dim,) or not np.all(size > 0):
        raise ScenarioError(
            f"scene {scene!r}: {name}: must be {dim} positive numbers (got {value!r})"
        )
    return size


def _floats(value: Any) -> np.ndarray | None:
    """``value`` as a float array, or ``None`` if it is not numeric (ragged, strings, ...)."""
    if isinstance(value, (str, bytes, dict)):
        return None
    try:
        array = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return None
    return array if np.isfinite(array).all() else None


def _cells(size_m: np.ndarray, resolution_m: float) -> tuple[int, ...]:
    return tuple(int(n) for n in np.maximum(np.round(size_m / resolution_m), 1))


def _raster_box(occupied: np.ndarray, resolution_m: float, lo: Sequence, hi: Sequence, value: bool):
    """Set the cells whose centres lie in the box ``[lo, hi)`` (origin at 0)."""
    index = []
    for axis, (a, b) in enumerate(zip(lo, hi, strict=True)):
        start = max(int(np.ceil(a / resolution_m - 0.5)), 0)
        stop = min(int(np.ceil(b / resolution_m - 0.5)), occupied.shape[axis])
        if stop <= start:
            return
        index.append(slice(start, stop))
    occupied[tuple(index)] = value


def _fill_pockets(occupied: np.ndarray) -> np.ndarray:
    """Mark free cells not face-connected to the largest free region as occupied."""
    labels, count = ndimage.label(~occupied)
    if count <= 1:
        return occupied
    sizes = np.bincount(labels.ravel())
    sizes[0] = 0
    return occupied | (labels != int(np.argmax(sizes)))


def surface_points(grid: OccupancyGrid, spacing_m: float | None = None) -> np.ndarray:
    """Obstacle points on obstacle surfaces, ``(m, dim)`` in world coordinates.

    A surface cell is an occupied cell with a free face-neighbour inside the
    grid (the grid's outer boundary is not a surface). With ``spacing_m``
    larger than the resolution, the surface cells are thinned to one per
    block of ``round(spacing_m / resolution_m)`` cells along each axis (a
    voxel-grid filter), which keeps about ``area / spacing_m**(dim-1)``
    points. Returned points are cell centres, so each lies in an occupied cell.
    """
    occupied = grid.occupied
    inner = ndimage.binary_erosion(occupied, border_value=1)
    cells = np.argwhere(occupied & ~inner)
    stride = 1 if spacing_m is None else max(int(round(spacing_m / grid.resolution_m)), 1)
    if stride > 1 and len(cells):
        _, keep = np.unique(cells // stride, axis=0, return_index=True)
        cells = cells[np.sort(keep)]
    return grid.to_world(cells).reshape(-1, grid.dim)


def _world(
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
        occupied = _fill_pockets(np.ascontiguousarray(occupied[:, :, iz]))
        meta = {**meta, "slice_height_m": slice_height_m}
    grid = OccupancyGrid(occupied, resolution_m, np.zeros(dim))
    points = surface_points(grid, point_spacing_m)
    return World(dim=dim, grid=grid, obstacle_points=points, name=name, meta=meta)


# --------------------------------------------------------------------------- scenes


@SCENES.register("free")
def free(rng: np.random.Generator | None = None, *, dim: int = 2, bounds_m: Any = None) -> World:
    """Obstacle-free space, unbounded or within ``bounds_m`` (``[[lo...], [hi...]]``)."""
    if dim not in (2, 3):
        raise ScenarioError(f"scene 'free': dim: must be 2 or 3 (got {dim!r})")
    if bounds_m is not None:
        bounds = _floats(bounds_m)
        if bounds is None or bounds.shape != (2, dim) or not np.all(bounds[1] > bounds[0]):
            raise ScenarioError(
                f"scene 'free': bounds_m: must be [[lower corner], [upper corner]] with "
                f"{dim} numbers each, upper > lower (got {bounds_m!r})"
            )
        bounds_m = bounds
    return World(dim=dim, bounds_m=bounds_m, name="free")


@SCENES.register("empty")
def empty(
    rng: np.random.Generator | None = None,
    *,
    size_m: Sequence[float] = OUTDOOR_SIZE_M,
    height_m: float = 10.0,
    resolution_m: float = 0.25,
) -> World:
    """The continuous paper's obstacle-free 3-D space (Sec. 4.1, Fig. 6).

    A ``size_m[0] x size_m[1] x height_m`` box (default 50 m x 70 m x 10 m, the
    paper gives no height) with an all-free grid, so grid-based planners work
    unchanged, and no obstacle points.
    """
    size = _check_size("empty", "size_m", size_m, 2)
    height = _check_positive("empty", "height_m", height_m)
    res = _check_positive("empty", "resolution_m", resolution_m)
    shape = _cells(np.append(size, height), res)
    grid = OccupancyGrid(np.zeros(shape, dtype=bool), res, np.zeros(3))
    return World(dim=3, grid=grid, obstacle_points=np.empty((0, 3)), name="empty")


def _partition(
    length: float, block_m: tuple[float, float], street_m: tuple[float, float], rng
) -> list[tuple[float, float]]:
    """Split ``[0, length]`` into blocks separated (and bordered) by streets."""
    spans: list[tuple[float, float]] = []
    cursor = rng.uniform(*street_m)
    while True:
        width = rng.uniform(*block_m)
        if cursor + width + street_m[0] > length:
            width = length - street_m[0] - cursor
            if width >= 0.5 * block_m[0]:
                spans.append((cursor, cursor + width))
            return spans
        spans.append((cursor, cursor + width))
        cursor += width + rng.uniform(*street_m)


def _split(lo: float, hi: float, lot_m: float, rng) -> list[tuple[float, float]]:
    """One or two lots along an axis of a block."""
    if hi - lo < 2 * lot_m:
        return [(lo, hi)]
    cut = lo + (hi - lo) * rng.uniform(0.4, 0.6)
    return [(lo, cut), (cut, hi)]


@SCENES.register("town")
def town(
    rng: np.random.Generator,
    *,
    size_m: Sequence[float] = OUTDOOR_SIZE_M,
    height_m: float = 10.0,
    resolution_m: float = 0.25,
    street_m: Sequence[float] = (4.0, 7.0),
    block_m: Sequence[float] = (8.0, 16.0),
    building_height_m: Sequence[float] = (4.0, 10.0),
    setback_m: float = 1.0,
    empty_lot_p: float = 0.15,
    point_spacing_m: float | None = None,
    dim: int = 3,
    slice_height_m: float = 2.0,
) -> World:
    """Part of a town: box buildings on blocks between streets (Sec. 4.1, Fig. 7).

    The area (default 50 m x 70 m, the paper's) is cut into blocks of
    ``block_m`` length by streets of ``street_m`` width, streets also along
    the border. Each block holds one to four lots; a lot is left empty (a
    square) with probability ``empty_lot_p``, otherwise it gets a box
    building set back up to ``setback_m`` from the lot's edges, with a height
    drawn from ``building_height_m``. Buildings as tall as ``height_m`` cannot
    be flown over. Enclosed free pockets are filled, so all free space is
    connected.

    Parameters
    ----------
    rng
        Source of all randomness.
    size_m, height_m, resolution_m
        Extent of the 3-D grid and its cell size.
    street_m, block_m, building_height_m
        ``[min, max]`` ranges drawn uniformly.
    point_spacing_m
        Spacing of the obstacle points on building surfaces; ``None`` (default)
        keeps one per surface cell, about 8 x 10^4 points for the default town
        (0.5 m gives about 2 x 10^4).
    dim, slice_height_m
        ``dim=2`` returns the horizontal slice at ``slice_height_m``.
    """
    size = _check_size("town", "size_m", size_m, 2)
    height = _check_positive("town", "height_m", height_m)
    res = _check_positive("town", "resolution_m", resolution_m)
    streets = _check_range("town", "street_m", street_m)
    blocks = _check_range("town", "block_m", block_m)
    heights = _check_range("town", "building_height_m", building_height_m)
    setback_m = _check_number("town", "setback_m", setback_m, 0.0, float("inf"))
    empty_lot_p = _check_number("town", "empty_lot_p", empty_lot_p, 0.0, 1.0)
    _check_common("town", dim, point_spacing_m, slice_height_m)
    occupied = np.zeros(_cells(np.append(size, height), res), dtype=bool)
    buildings: list[list[float]] = []
    lot_m = 0.5 * blocks[0]
    for x0, x1 in _partition(size[0], blocks, streets, rng):
        for y0, y1 in _partition(size[1], blocks, streets, rng):
            for lx0, lx1 in _split(x0, x1, lot_m, rng):
                for ly0, ly1 in _split(y0, y1, lot_m, rng):
                    if rng.random() < empty_lot_p:
                        continue
                    back = rng.uniform(0.0, setback_m, size=4)
                    bx0, bx1 = lx0 + back[0], lx1 - back[1]
                    by0, by1 = ly0 + back[2], ly1 - back[3]
                    h = min(rng.uniform(*heights), height)
                    if bx1 - bx0 < res or by1 - by0 < res:
                        continue
                    _raster_box(occupied, res, (bx0, by0, 0.0), (bx1, by1, h), True)
                    buildings.append([bx0, by0, bx1, by1, h])
    occupied = _fill_pockets(occupied)
    meta = {"scene": "town", "buildings": buildings}
    return _world(
        occupied,
        res,
        "town",
        meta,
        dim=dim,
        slice_height_m=slice_height_m,
        point_spacing_m=point_spacing_m,
    )


def _rooms_along(
    y0: float, y1: float, room_m: tuple[float, float], rng
) -> list[tuple[float, float]]:
    """Consecutive room spans along the corridor; the last one takes the rest."""
    spans: list[tuple[float, float]] = []
    cursor = y0
    while y1 - cursor >= 2 * room_m[0]:
        width = min(rng.uniform(*room_m), y1 - cursor - room_m[0])
        spans.append((cursor, cursor + width))
        cursor += width
    spans.append((cursor, y1))
    return spans


@SCENES.register("office")
def office(
    rng: np.random.Generator,
    *,
    size_m: Sequence[float] = OFFICE_SIZE_M,
    height_m: float = 3.0,
    resolution_m: float = 0.1,
    corridor_m: float = 2.0,
    room_m: Sequence[float] = (3.0, 5.0),
    door_m: float = 1.0,
    door_height_m: float = 2.2,
    wall_m: float = 0.2,
    point_spacing_m: float | None = None,
    dim: int = 3,
    slice_height_m: float = 1.0,
) -> World:
    """An office floor: rooms on both sides of a corridor, one door each (Sec. 4.1, Fig. 8).

    The floor (default 10 m x 15 m, the paper's "about 10m x 15m") is closed
    by outer walls. A corridor of width ``corridor_m`` runs along the long
    (y) axis, its centre shifted randomly by up to 0.5 m. On each side,
    partition walls cut rooms of ``room_m`` width; each room has a door of
    width ``door_m`` and height ``door_height_m`` into the corridor, at a
    random place. The default door (1 m) lets the paper's 0.5 m quadrotors
    through with the office's obstacle clearance ``R_o = 0.25 m`` (Table 2).

    ``meta`` holds ``rooms`` and ``doors`` as ``[x0, y0, x1, y1]`` boxes and
    ``corridor`` likewise; ``dim=2`` returns the slice at ``slice_height_m``.
    """
    size = _check_size("office", "size_m", size_m, 2)
    height = _check_positive("office", "height_m", height_m)
    res = _check_positive("office", "resolution_m", resolution_m)
    corridor = _check_positive("office", "corridor_m", corridor_m)
    rooms_range = _check_range("office", "room_m", room_m)
    door = _check_positive("office", "door_m", door_m)
    door_h = _check_positive("office", "door_height_m", door_height_m)
    wall = _check_positive("office", "wall_m", wall_m)
    _check_common("office", dim, point_spacing_m, slice_height_m)
    width, length = size
    depth = (width - corridor) / 2 - 2 * wall  # room depth on each side
    if depth < door or rooms_range[0] < door + 2 * wall:
        raise ScenarioError(
            f"scene 'office': size_m/corridor_m/room_m: rooms too small for {door} m doors "
            f"(room depth {depth:.2f} m, min room width {rooms_range[0]} m)"
        )
    occupied = np.zeros(_cells(np.append(size, height), res), dtype=bool)
    full = (0.0, height)
    # outer walls
    for lo, hi in (
        ((0, 0), (wall, length)),
        ((width - wall, 0), (width, length)),
        ((0, 0), (width, wall)),
        ((0, length - wall), (width, length)),
    ):
        _raster_box(occupied, res, (*lo, full[0]), (*hi, full[1]), True)
    cx = width / 2 + rng.uniform(-0.5, 0.5) * min(1.0, depth - door)
    left_x, right_x = cx - corridor / 2, cx + corridor / 2
    rooms: list[list[float]] = []
    doors: list[list[float]] = []
    sides = (
        (left_x - wall, left_x, wall, left_x - wall),
        (right_x, right_x + wall, right_x + wall, width - wall),
    )
    for wall_x0, wall_x1, room_x0, room_x1 in sides:
        _raster_box(occupied, res, (wall_x0, 0, 0), (wall_x1, length, height), True)
        spans = _rooms_along(wall, length - wall, rooms_range, rng)
        for k, (y0, y1) in enumerate(spans):
            if k > 0:  # partition wall centred on the boundary
                _raster_box(
                    occupied,
                    res,
                    (room_x0, y0 - wall / 2, 0),
                    (room_x1, y0 + wall / 2, height),
                    True,
                )
            inner0 = y0 + (wall / 2 if k > 0 else 0.0)
            inner1 = y1 - (wall / 2 if k < len(spans) - 1 else 0.0)
            rooms.append([room_x0, inner0, room_x1, inner1])
            dy = (
                rng.uniform(inner0 + 0.1, inner1 - 0.1 - door)
                if inner1 - inner0 > door + 0.2
                else inner0
            )
            doors.append([wall_x0, dy, wall_x1, dy + door])
            _raster_box(
                occupied, res, (wall_x0 - res, dy, 0), (wall_x1 + res, dy + door, door_h), False
            )
    meta = {
        "scene": "office",
        "rooms": rooms,
        "doors": doors,
        "corridor": [left_x, wall, right_x, length - wall],
        "door_height_m": door_h,
    }
    occupied = _fill_pockets(occupied)
    return _world(
        occupied,
        res,
        "office",
        meta,
        dim=dim,
        slice_height_m=slice_height_m,
        point_spacing_m=point_spacing_m,
    )


@SCENES.register("map")
def map_scene(
    rng: np.random.Generator | None = None,
    *,
    path: str,
    resolution_m: float | None = None,
    origin_m: Any = None,
    occupied_thresh: float = 0.65,
    free_thresh: float = 0.196,
    negate: bool = False,
) -> World:
    """A 2-D world from a map file (PNG/PGM image or ROS map_server YAML).

    Parameters are those of :func:`tether.world.maps.load_map`; unknown cells
    are obstacles. Obstacle points are the centres of the obstacles' boundary
    cells.
    """
    grid = load_map(
        path,
        resolution_m=resolution_m,
        origin_m=origin_m,
        occupied_thresh=occupied_thresh,
        free_thresh=free_thresh,
        negate=negate,
    )
    points = surface_points(grid)
    return World(dim=2, grid=grid, obstacle_points=points, name="map", meta={"path": str(path)})


@SCENES.register("user_points")
def user_points(
    rng: np.random.Generator | None = None,
    *,
    path: str,
    bounds_m: Any = None,
    resolution_m: float = 0.25,
    margin_m: float = 2.0,
) -> World:
    """A world from a file of obstacle points (``.npy``, ``.csv``, ``.xyz``; x y [z]).

    The grid covers ``bounds_m`` (``[[lower corner], [upper corner]]``), by
    default the points' bounding box grown by ``margin_m``; a cell holding a
    point is occupied. Points outside the bounds are dropped; the world's
    obstacle points are the remaining user points themselves.
    """
    points = load_points(path)
    dim = points.shape[1]
    res = _check_positive("user_points", "resolution_m", resolution_m)
    if bounds_m is None:
        margin = max(_check_number("user_points", "margin_m", margin_m, 0.0, float("inf")), res)
        bounds = np.stack([points.min(axis=0) - margin, points.max(axis=0) + margin])
    else:
        bounds = _floats(bounds_m)
        if bounds is None or bounds.shape != (2, dim) or not np.all(bounds[1] > bounds[0]):
            raise MapError(
                f"{path}: bounds_m: must be [[lower corner], [upper corner]] with {dim} "
                f"numbers each (the file's points are {dim}-D), upper > lower (got {bounds_m!r})"
            )
    grid = OccupancyGrid.from_points(points, bounds, res)
    keep = grid.inside(grid.to_cell(points))
    if not keep.any():
        raise MapError(
            f"{path}: bounds_m: none of the {len(points)} points lies inside {bounds.tolist()}; "
            "widen the bounds or omit them"
        )
    world = World(
        dim=dim,
        bounds_m=grid.bounds_m,
        grid=grid,
        obstacle_points=points[keep],
        name="user_points",
        meta={"path": str(path), "dropped_points": int((~keep).sum())},
    )
    return world


# --------------------------------------------------------------------------- utilities


def make_scene(name: str, rng: np.random.Generator | int | None = None, **params: Any) -> World:
    """Build a registered scene by name, with one-line errors for bad names/parameters.

    ``rng`` may be a Generator or a seed. A ``seed`` parameter (an int), if
    given, replaces ``rng``: it fixes a procedural layout independently of the
    run's seed (``world.params.seed`` in a scenario).
    """
    seed = params.pop("seed", None)
    if seed is not None:
        if isinstance(seed, bool) or not isinstance(seed, int) or seed < 0:
            raise ScenarioError(f"scene {name!r}: seed must be a non-negative int, got {seed!r}")
        rng = seed
    if name not in SCENES:
        raise ScenarioError(
            f"scene {name!r}: unknown; expected one of: {', '.join(SCENES.names())}"
        )
    factory = SCENES.get(name)
    accepted = [p for p in inspect.signature(factory).parameters if p != "rng"]
    unknown = sorted(set(params) - set(accepted))
    if unknown:
        raise ScenarioError(
            f"scene {name!r}: unknown parameter(s) {', '.join(unknown)}; "
            f"accepted: {', '.join(accepted + ['seed'])}"
        )
    return factory(np.random.default_rng(rng), **params)


def free_positions(
    world: World,
    n: int,
    rng: np.random.Generator,
    clearance_m: float = 0.0,
    *,
    same_component: bool = False,
) -> np.ndarray:
    """``n`` random points, uniform over the free space with ``clearance_m``.

    A point counts as free exactly as :meth:`World.points_free` says (cell
    distance field ``>= clearance_m``, inside the bounds). With
    ``same_component`` the points are drawn from the largest face-connected
    region of such cells, so a grid planner can connect any two of them.

    Raises
    ------
    ScenarioError
        No cell has the requested clearance, or the world is unbounded.
    """
    if world.bounds_m is None:
        raise ScenarioError("free_positions: the world is unbounded; give the scene bounds_m")
    lo, hi = world.bounds_m
    if world.grid is None:
        return rng.uniform(lo, hi, size=(n, world.dim))
    grid = world.grid
    ok = grid.distance_field_m >= clearance_m if clearance_m > 0 else ~grid.occupied
    # keep only cells that lie wholly inside the world's bounds
    for axis in range(grid.dim):
        edges = grid.origin_m[axis] + grid.resolution_m * np.arange(grid.shape[axis] + 1)
        inside = (edges[:-1] >= lo[axis] - 1e-9) & (edges[1:] <= hi[axis] + 1e-9)
        shape = [1] * grid.dim
        shape[axis] = -1
        ok &= inside.reshape(shape)
    if same_component and ok.any():
        labels, _ = ndimage.label(ok)
        sizes = np.bincount(labels.ravel())
        sizes[0] = 0
        ok = labels == int(np.argmax(sizes))
    cells = np.flatnonzero(ok)
    if len(cells) == 0:
        raise ScenarioError(
            f"free_positions: no free cell with clearance {clearance_m} m in scene "
            f"{world.name!r}; lower the clearance"
        )
    pick = np.stack(np.unravel_index(rng.choice(cells, size=n), grid.shape), axis=1)
    jitter = 0.5 + (rng.random((n, grid.dim)) - 0.5) * (1 - 1e-6)
    return grid.origin_m + (pick + jitter) * grid.resolution_m
