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
``map``         2/3   a PNG/PGM or ROS YAML map file (:func:`~tether.world.maps.load_map`);
                      in 3-D its obstacles are walls up to ``height_m``
``user_points`` 2/3   obstacle points from a ``.npy``/``.csv``/``.xyz`` file
=============== ===== =======================================================

The 3-D scenes come with a 3-D :class:`~tether.world.grid.OccupancyGrid` and a
matching obstacle point set (the paper's set ``O`` of obstacle points, Sec. 2):
centres of occupied cells on obstacle *surfaces*, thinned to about one point
per ``point_spacing_m``, so every point lies in an occupied cell.
"""

from __future__ import annotations

import inspect
import warnings
from collections.abc import Sequence
from typing import Any

import numpy as np
from scipy import ndimage
from scipy.spatial import cKDTree

from tether.config import MAX_LENGTH_M
from tether.errors import MapError, ScenarioError, TetherWarning
from tether.registry import SCENES
from tether.suggest import did_you_mean
from tether.world.extrude import coarsen, extrude
from tether.world.grid import OccupancyGrid
from tether.world.maps import load_map
from tether.world.points import load_points
from tether.world.procedural import office, town
from tether.world.scene_kit import (
    OUTDOOR_SIZE_M,
    cells_of,
    check_number,
    check_positive,
    check_size,
    floats,
)
from tether.world.world import World

__all__ = [
    "empty",
    "free",
    "free_positions",
    "make_scene",
    "map_scene",
    "office",
    "town",
    "user_points",
]


# --------------------------------------------------------------------------- helpers


# --------------------------------------------------------------------------- scenes


@SCENES.register("free")
def free(rng: np.random.Generator | None = None, *, dim: int = 2, bounds_m: Any = None) -> World:
    """Obstacle-free space, unbounded or within ``bounds_m`` (``[[lo...], [hi...]]``).

    Parameters
    ----------
    rng
        Unused (the scene has no random choice).
    dim
        Dimension of the space (``world.dim``).
    bounds_m
        ``[[lower corner], [upper corner]]`` in m; ``None``: unbounded.
    """
    if dim not in (2, 3):
        raise ScenarioError(f"scene 'free': dim: must be 2 or 3 (got {dim!r})")
    if bounds_m is not None:
        bounds = floats(bounds_m)
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

    Parameters
    ----------
    rng
        Unused (the scene has no random choice).
    size_m
        Extent ``[x, y]`` of the box in m.
    height_m
        Height of the box in m.
    resolution_m
        Cell size of the grid in m.
    """
    size = check_size("empty", "size_m", size_m, 2)
    height = check_positive("empty", "height_m", height_m)
    res = check_positive("empty", "resolution_m", resolution_m)
    shape = cells_of(np.append(size, height), res, "empty")
    grid = OccupancyGrid(np.zeros(shape, dtype=bool), res, np.zeros(3))
    return World(dim=3, grid=grid, obstacle_points=np.empty((0, 3)), name="empty")


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
    dim: int = 2,
    height_m: float | None = None,
    cell_m: float | None = None,
    point_spacing_m: float | None = None,
) -> World:
    """A world from a map file (PNG/PGM image or ROS map_server YAML), 2-D or raised to 3-D.

    Parameters are those of :func:`tether.world.maps.load_map`; unknown cells are
    obstacles. ``cell_m`` (a whole multiple of the map's resolution) makes the cells
    coarser: a coarse cell is an obstacle when any of its pixels is. With ``dim: 3`` the
    map is a building: every obstacle cell a wall from the floor (``z = 0``) to the
    ceiling ``height_m`` (rounded up to whole cells), which are the world's vertical
    bounds (:func:`tether.world.extrude.extrude`). Obstacle points are the centres of the
    obstacles' boundary cells (in 3-D, the walls' faces), thinned to about one per
    ``point_spacing_m`` if given.

    Parameters
    ----------
    rng
        Unused (the scene has no random choice).
    path
        The map file: PNG/PGM image or ROS map_server YAML.
    resolution_m
        Cell size in m; overrides the YAML's (an image alone: 1 m per pixel).
    origin_m
        ``[x, y]`` of the lower-left corner in m; overrides the YAML's.
    occupied_thresh
        Occupancy probability above which a pixel is an obstacle, in [0, 1].
    free_thresh
        Occupancy probability below which a pixel is free, in [0, 1].
    negate
        Dark pixels are free, light ones occupied.
    dim
        2, or 3 to raise the obstacles to walls (``world.dim``).
    height_m
        3-D only: the ceiling, the walls' height in m.
    cell_m
        Coarser cells in m, a whole multiple of the map's resolution.
    point_spacing_m
        Obstacle points thinned to about one per this distance in m.
    """
    if dim not in (2, 3) or isinstance(dim, bool):
        raise ScenarioError(f"scene 'map': dim: must be 2 or 3 (got {dim!r})")
    if dim == 2 and height_m is not None:
        raise ScenarioError(
            "scene 'map': height_m: a 2-D map has no height; set world.dim: 3 to raise its "
            "obstacles to walls, or remove height_m"
        )
    if dim == 3 and height_m is None:
        raise ScenarioError(
            "scene 'map': height_m: a 3-D map needs the height of its walls (the ceiling), "
            "e.g. height_m: 3.0"
        )
    if height_m is not None:
        check_number("map", "height_m", height_m, 1e-6, 1e4)
    if cell_m is not None:
        check_positive("map", "cell_m", cell_m)
    if point_spacing_m is not None:
        check_positive("map", "point_spacing_m", point_spacing_m)
    grid = load_map(
        path,
        resolution_m=resolution_m,
        origin_m=origin_m,
        occupied_thresh=occupied_thresh,
        free_thresh=free_thresh,
        negate=negate,
    )
    if cell_m is not None:
        grid = coarsen(grid, cell_m)
    meta: dict[str, Any] = {"path": str(path)}
    if dim == 3:
        grid = extrude(grid, height_m)
        meta["height_m"] = float(grid.size_m[2])
    points = grid.surface_points(point_spacing_m)
    return World(dim=dim, grid=grid, obstacle_points=points, name="map", meta=meta)


@SCENES.register("user_points")
def user_points(
    rng: np.random.Generator | None = None,
    *,
    path: str,
    bounds_m: Any = None,
    resolution_m: float = 0.25,
    margin_m: float = 2.0,
    floor_m: float | None = None,
    ceiling_m: float | None = None,
    inflate_m: float = 0.0,
) -> World:
    """A world from a file of obstacle points (``.npy``, ``.csv``, ``.xyz``; x y [z]).

    The grid covers ``bounds_m`` (``[[lower corner], [upper corner]]``), by default the
    points' box grown by ``margin_m`` in x and y; in 3-D from the floor ``floor_m``
    (default: the lowest point) to the ceiling ``ceiling_m`` (default: the top of the
    cells holding the highest points, so nothing passes above the tallest obstacle).
    A cell holding a point is occupied, and so is every cell within ``inflate_m`` of one:
    points sampling a wall make it solid when neighbours are at most ``resolution_m``
    apart (else give ``inflate_m`` about half their spacing); sparser points are warned
    about (:class:`~tether.errors.TetherWarning`). Points outside the bounds are dropped.
    The world's obstacle points are the remaining user points (with ``inflate_m``, the
    faces of the inflated obstacles).

    Parameters
    ----------
    rng
        Unused (the scene has no random choice).
    path
        The point file: ``.npy``, ``.csv`` or ``.xyz`` rows of x y [z] in m.
    bounds_m
        ``[[lower corner], [upper corner]]`` of the grid in m; ``None``: from the points.
    resolution_m
        Cell size of the grid in m.
    margin_m
        Default bounds: the points' box grown by this in x and y, in m.
    floor_m
        3-D: the lowest z of the grid in m (default: the lowest point).
    ceiling_m
        3-D: the highest z of the grid in m (default: above the highest points' cells).
    inflate_m
        Cells within this distance of a point are obstacles too, in m.
    """
    points = load_points(path)
    dim = points.shape[1]
    res = check_positive("user_points", "resolution_m", resolution_m)
    inflate = check_number("user_points", "inflate_m", inflate_m, 0.0, 1e4)
    bounds = _point_bounds(path, points, bounds_m, res, margin_m, floor_m, ceiling_m)
    try:
        grid = OccupancyGrid.from_points(points, bounds, res)
    except ValueError as exc:
        raise MapError(f"{path}: resolution_m: {exc}") from None
    keep = grid.inside(grid.to_cell(points))
    if not keep.any():
        raise MapError(
            f"{path}: bounds_m: none of the {len(points)} points lies inside {bounds.tolist()}; "
            "widen the bounds or omit them"
        )
    warn_sparse(path, points[keep], res, inflate)
    obstacle_points = points[keep]
    if inflate > 0:
        grown = ndimage.distance_transform_edt(~grid.occupied) * res <= inflate
        grid = OccupancyGrid(grown, res, grid.origin_m)
        obstacle_points = grid.surface_points()
    return World(
        dim=dim,
        bounds_m=grid.bounds_m,
        grid=grid,
        obstacle_points=obstacle_points,
        name="user_points",
        meta={"path": str(path), "dropped_points": int((~keep).sum())},
    )


def _point_bounds(
    path: str,
    points: np.ndarray,
    bounds_m: Any,
    res: float,
    margin_m: Any,
    floor_m: Any,
    ceiling_m: Any,
) -> np.ndarray:
    """The ``(2, dim)`` bounds of a point cloud's world (see :func:`user_points`)."""
    dim = points.shape[1]
    if dim == 2 and (floor_m is not None or ceiling_m is not None):
        name = "floor_m" if floor_m is not None else "ceiling_m"
        raise MapError(f"{path}: {name}: the file's points are 2-D (x y): they have no "
                       f"floor or ceiling; remove {name}")  # fmt: skip
    if bounds_m is not None:
        if floor_m is not None or ceiling_m is not None:
            raise MapError(f"{path}: bounds_m: give bounds_m or floor_m / ceiling_m, not both "
                           "(bounds_m holds the floor and ceiling as its z)")  # fmt: skip
        bounds = floats(bounds_m)
        if bounds is None or bounds.shape != (2, dim) or not np.all(bounds[1] > bounds[0]):
            raise MapError(
                f"{path}: bounds_m: must be [[lower corner], [upper corner]] with {dim} "
                f"numbers each (the file's points are {dim}-D), upper > lower (got {bounds_m!r})"
            )
        return bounds
    margin = max(check_number("user_points", "margin_m", margin_m, 0.0, float("inf")), res)
    bounds = np.stack([points.min(axis=0) - margin, points.max(axis=0) + margin])
    if dim == 3:
        z = points[:, 2]
        lo = z.min()
        if floor_m is not None:
            lo = check_number("user_points", "floor_m", floor_m, -MAX_LENGTH_M, MAX_LENGTH_M)
        if ceiling_m is None:  # the top of the cells that hold the highest points
            hi = lo + (np.floor((z.max() - lo) / res) + 1) * res
        else:
            hi = check_number("user_points", "ceiling_m", ceiling_m, -MAX_LENGTH_M, MAX_LENGTH_M)
        if not hi > lo:
            raise MapError(f"{path}: ceiling_m: must be above the floor {lo:g} m (got {hi:g})")
        bounds[:, 2] = lo, hi
    return bounds


#: the most points whose spacing :func:`warn_sparse` measures (a random sample beyond)
SPACING_SAMPLE = 20_000


def warn_sparse(path: str, points: np.ndarray, resolution_m: float, inflate_m: float) -> None:
    """Warn when points sit farther apart than a cell (+ inflation): walls would have gaps.

    The spacing is the median distance from a point to its nearest neighbour (over a
    sample of :data:`SPACING_SAMPLE` points); more than ``resolution_m + 2 inflate_m``
    leaves free cells between neighbouring points of one wall.
    """
    if len(points) < 2:
        return
    sample = points
    if len(points) > SPACING_SAMPLE:
        pick = np.random.default_rng(0).choice(len(points), SPACING_SAMPLE, replace=False)
        sample = points[pick]
    spacing = float(np.median(cKDTree(points).query(sample, k=2)[0][:, 1]))
    if spacing > resolution_m + 2 * inflate_m:
        warnings.warn(
            TetherWarning(
                f"{path}: points are {spacing:.3g} m apart (median to the nearest), more than "
                f"resolution_m {resolution_m:g}: walls sampled this sparsely have gaps robots "
                f"can pass; give resolution_m >= {spacing:.3g} or inflate_m: "
                f"{spacing / 2:.3g}"
            ),
            stacklevel=2,
        )


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
    if unknown:  # named first, so that the scenario's error names it as its field
        raise ScenarioError(
            f"{unknown[0]}: unknown parameter of scene {name!r}"
            f"{did_you_mean(unknown[0], [*accepted, 'seed'])}; remove it or check its "
            f"spelling (accepted: {', '.join([*accepted, 'seed'])})"
        )
    required = [
        p.name
        for p in inspect.signature(factory).parameters.values()
        if p.default is inspect.Parameter.empty
        and p.kind in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD)
        and p.name != "rng"
    ]
    missing = [p for p in required if p not in params]
    if missing:
        raise ScenarioError(
            f"scene {name!r}: missing parameter(s) {', '.join(missing)}; "
            f"e.g. world.params.{missing[0]}"
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
