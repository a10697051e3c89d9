"""A* shortest paths on 2-D/3-D occupancy grids, and metric planning on a world.

The continuous-connectivity paper (Nestmeyer et al., *Decentralized simultaneous
multi-target exploration using a connected network of multiple robots*, Sec. 3.2)
plans a path to a target in two steps: "the known portion of the map is discretized
into an equally spaced grid in 3D with a cell size of Rgrid. A cell is marked as
occupied whenever an obstacle lies inside a radius of Rgrid around the cell. On this
grid, a shortest path is found via A*." The waypoints are then smoothed by a B-spline
(:mod:`tether.paths.bspline`).

This module is the first step: :func:`astar_grid` on a boolean free mask, and
:func:`plan_path`, which builds the paper's planning grid from a
:class:`~tether.world.world.World` or :class:`~tether.world.grid.OccupancyGrid`
(:func:`planning_grid`) and returns metric waypoints.

Implementation: cells are flat integer indices into a grid padded by one blocked
cell on every side, so a neighbour is ``i + offset`` with no bounds check; the open
list is a :mod:`heapq` of ``(f, h, i)`` tuples (lazy deletion of stale entries), and
``g``, the heuristic, the parents and the closed set are flat Python lists/bytearrays
(faster to index one element at a time than numpy arrays).
"""

from __future__ import annotations

import heapq
import itertools
import math
from collections.abc import Sequence

import numpy as np
from scipy import ndimage

from tether import jit
from tether.world.grid import OccupancyGrid
from tether.world.world import World

__all__ = [
    "PLANNING_BYTES_PER_CELL",
    "astar_grid",
    "neighbour_offsets",
    "plan_path",
    "planning_grid",
    "planning_shape",
]

_CONNECTIVITY = ("full", "face")
_HEURISTICS = ("octile", "euclidean")
# planning cells whose lower bound on the obstacle distance is within this of the
# inflation radius still count as free (the distance field is a float sqrt)
_TIE_M = 1e-9
#: peak bytes per planning cell of :func:`planning_grid` and an A* search on it (measured
#: about 150 for building the 3-D grid and up to 50 for a search across it; rounded up)
PLANNING_BYTES_PER_CELL = 200


def neighbour_offsets(dim: int, connectivity: str = "full") -> np.ndarray:
    """Integer steps to the neighbours of a cell, ``(k, dim)``, in a fixed order.

    ``"full"``: every cell sharing a face, edge or corner (8 in 2-D, 26 in 3-D);
    ``"face"``: cells sharing a face (4 in 2-D, 6 in 3-D). The order is
    lexicographic in the offsets, which fixes the tie-breaking of :func:`astar_grid`.
    """
    if dim not in (2, 3):
        raise ValueError("dim must be 2 or 3")
    if connectivity not in _CONNECTIVITY:
        raise ValueError(f"connectivity must be one of {_CONNECTIVITY}, not {connectivity!r}")
    steps = np.array(list(itertools.product((-1, 0, 1), repeat=dim)), dtype=np.intp)
    nonzero = np.abs(steps).sum(axis=1)
    keep = nonzero > 0 if connectivity == "full" else nonzero == 1
    return steps[keep]


def _heuristic(delta: np.ndarray, connectivity: str, heuristic: str) -> np.ndarray:
    """Cost-to-go lower bound from cell differences ``delta`` (``(n, dim)``, in cells).

    ``"euclidean"``: ``|delta|``. ``"octile"``: the exact cost of the shortest path on
    the *obstacle-free* lattice (with ``d1 >= d2 >= d3`` the sorted ``|delta|``:
    ``sqrt(3) d3 + sqrt(2) (d2 - d3) + (d1 - d2)`` in 3-D, ``sqrt(2) d2 + (d1 - d2)``
    in 2-D, ``d1 + d2 + d3`` for face connectivity). Both are admissible and
    consistent; the octile one is never below the Euclidean one, so A* with it
    expands a subset of the cells (far fewer in open space).
    """
    a = np.abs(delta).astype(float)
    if heuristic == "euclidean":
        return np.sqrt((a * a).sum(axis=1))
    if connectivity == "face":
        return a.sum(axis=1)
    a = -np.sort(-a, axis=1)  # descending
    if a.shape[1] == 2:
        return math.sqrt(2.0) * a[:, 1] + (a[:, 0] - a[:, 1])
    return math.sqrt(3.0) * a[:, 2] + math.sqrt(2.0) * (a[:, 1] - a[:, 2]) + (a[:, 0] - a[:, 1])


#: the last mask's component labels: a planner asks many paths on one planning grid
_LABELS: dict[str, object] = {"key": None, "labels": None}


def _labels(free: np.ndarray, connectivity: str) -> np.ndarray:
    """Connected components of the free cells (``scipy.ndimage.label``), reused per mask."""
    key = (free.shape, connectivity, free.tobytes())
    if _LABELS["key"] != key:
        full = connectivity == "full"
        structure = ndimage.generate_binary_structure(free.ndim, free.ndim if full else 1)
        _LABELS["key"], _LABELS["labels"] = key, ndimage.label(free, structure=structure)[0]
    return _LABELS["labels"]  # type: ignore[return-value]


def astar_grid(
    free: np.ndarray,
    start_cell: Sequence[int] | np.ndarray,
    goal_cell: Sequence[int] | np.ndarray,
    *,
    connectivity: str = "full",
    heuristic: str = "octile",
) -> np.ndarray | None:
    """Shortest grid path by A* (continuous-connectivity paper, Sec. 3.2).

    Moves go from a free cell to a free neighbour (:func:`neighbour_offsets`) and
    cost the Euclidean length of the step in cells (1, sqrt(2), sqrt(3)); diagonal
    steps between two blocked cells are allowed (the paper's inflation by ``Rgrid``
    keeps them clear of obstacles, see :func:`plan_path`). The returned path has the least total
    cost (A* with a consistent heuristic closes every cell at its final cost).

    Parameters
    ----------
    free
        Boolean mask, 2-D ``(nx, ny)`` or 3-D ``(nx, ny, nz)``; ``True`` = traversable.
    start_cell, goal_cell
        Integer cell indices (length ``free.ndim``).
    connectivity
        ``"full"`` (8 neighbours in 2-D, 26 in 3-D, the paper's) or ``"face"``
        (4 / 6 neighbours).
    heuristic
        ``"octile"`` (default: the exact free-lattice distance, admissible,
        consistent and at least the Euclidean distance) or ``"euclidean"``.

    Returns
    -------
    numpy.ndarray or None
        ``(k, dim)`` integer cells from ``start_cell`` to ``goal_cell`` inclusive,
        consecutive cells neighbours; ``None`` when the goal cannot be reached or
        either end is blocked or outside the grid.

    Notes
    -----
    Time ``O(E log V)`` for ``V`` cells and ``E = 26 V`` (3-D) moves in the worst
    case, memory ``O(V)``; in open space the octile heuristic expands about the
    cells of one shortest path. Ties are broken deterministically: lowest
    ``f = g + h``, then lowest ``h`` (closest to the goal), then lowest flat index
    (C order), with neighbours scanned in :func:`neighbour_offsets` order.
    Its time, compiled and reference, on 100 x 100 x 20 grids with box buildings:
    the ``paths`` row of ``python benchmarks/run.py`` (docs/explanation/paths.md).
    """
    free = np.asarray(free, dtype=bool)
    dim = free.ndim
    if dim not in (2, 3):
        raise ValueError("free must be a 2-D or 3-D boolean array")
    if heuristic not in _HEURISTICS:
        raise ValueError(f"heuristic must be one of {_HEURISTICS}, not {heuristic!r}")
    start = np.asarray(start_cell, dtype=np.intp).reshape(-1)
    goal = np.asarray(goal_cell, dtype=np.intp).reshape(-1)
    if len(start) != dim or len(goal) != dim:
        raise ValueError(f"start_cell and goal_cell need {dim} indices")
    offsets = neighbour_offsets(dim, connectivity)
    shape = np.asarray(free.shape)
    for cell in (start, goal):
        if np.any(cell < 0) or np.any(cell >= shape) or not free[tuple(cell)]:
            return None
    if np.array_equal(start, goal):
        return start[None, :].copy()
    # unreachable goals would make A* close the start's whole component: label the
    # components first (scipy.ndimage, C speed) and answer None at once
    labels = _labels(free, connectivity)
    if labels[tuple(start)] != labels[tuple(goal)]:
        return None

    # pad by one blocked cell on each side: neighbours of real cells are always in range
    padded = np.zeros(tuple(shape + 2), dtype=bool)
    padded[tuple(slice(1, -1) for _ in range(dim))] = free
    pshape = padded.shape
    strides = np.array([int(np.prod(pshape[k + 1 :])) for k in range(dim)], dtype=np.intp)
    s_idx = int((start + 1) @ strides)
    g_idx = int((goal + 1) @ strides)
    if jit.enabled():  # the same search, compiled (same keys, same heap order, same path)
        from tether.paths.astar_kernels import astar_kernel

        flat = astar_kernel(
            padded.ravel(), strides.astype(np.int64), (offsets @ strides).astype(np.int64),
            np.sqrt((offsets * offsets).sum(axis=1).astype(float)), s_idx, g_idx,
            (goal + 1).astype(np.int64), connectivity == "face", heuristic == "euclidean",
        )  # fmt: skip
        return np.stack(np.unravel_index(flat, pshape), axis=1) - 1

    # heuristic of every padded cell, in cells (vectorised once; O(V))
    coords = np.indices(pshape, dtype=np.intp).reshape(dim, -1).T
    h_all = _heuristic(coords - (goal + 1), connectivity, heuristic).tolist()
    # g doubles as the closed set: -inf marks obstacles, padding and closed cells, so
    # a relaxation ``ng < g[n]`` needs no other test (a closed cell's g is final)
    g_cost = np.where(padded, math.inf, -math.inf).ravel().tolist()
    parent = [-1] * len(g_cost)
    moves = [(int(o @ strides), math.sqrt(float(o @ o))) for o in offsets]
    closed = -math.inf

    heap = [(h_all[s_idx], h_all[s_idx], s_idx)]
    g_cost[s_idx] = 0.0
    pop, push = heapq.heappop, heapq.heappush
    found = False
    while heap:
        _, _, i = pop(heap)
        gi = g_cost[i]
        if gi == closed:
            continue  # stale entry of a closed cell
        if i == g_idx:
            found = True
            break
        g_cost[i] = closed  # with a consistent heuristic its g is final
        for off, step in moves:
            n = i + off
            ng = gi + step
            if ng < g_cost[n]:
                g_cost[n] = ng
                parent[n] = i
                hn = h_all[n]
                push(heap, (ng + hn, hn, n))
    if not found:
        return None
    chain = [g_idx]
    while chain[-1] != s_idx:
        chain.append(parent[chain[-1]])
    flat = np.array(chain[::-1], dtype=np.intp)
    return np.stack(np.unravel_index(flat, pshape), axis=1) - 1


# ------------------------------------------------------------------ metric planning


def _occupancy(world_or_grid: World | OccupancyGrid) -> OccupancyGrid | None:
    if isinstance(world_or_grid, OccupancyGrid):
        return world_or_grid
    if isinstance(world_or_grid, World):
        return world_or_grid.grid
    raise TypeError(f"expected a World or an OccupancyGrid, not {type(world_or_grid).__name__}")


def planning_shape(size_m: np.ndarray, cell_m: float) -> np.ndarray:
    """Cells per axis of the planning grid of cell ``cell_m`` over ``size_m``, as floats.

    Floats, so that a tiny ``cell_m`` gives a huge (or infinite) count to refuse,
    not an integer overflow; :func:`planning_grid` uses the same numbers.
    """
    with np.errstate(over="ignore", divide="ignore"):
        return np.maximum(np.ceil(np.asarray(size_m, dtype=float) / cell_m - 1e-9), 1)


def planning_grid(
    world_or_grid: World | OccupancyGrid, *, cell_m: float, inflate_m: float | None = None
) -> OccupancyGrid:
    """The paper's planning grid (Sec. 3.2): cells of ``cell_m`` (``Rgrid``), inflated.

    The planning grid shares the origin of the world's occupancy grid and covers
    it (the last row of cells may stick out). A planning cell is **occupied** when

    * its centre lies outside the world's grid, or
    * an occupied cell centre of the world's grid may lie closer than ``inflate_m``
      to the planning cell's centre: with ``f`` the world-grid cell containing the
      centre ``p`` and ``DF`` the world grid's distance field (distance from a cell
      centre to the nearest occupied cell centre, ``OccupancyGrid.distance_field_m``),
      the cell is occupied when ``DF(f) - |p - centre(f)| < inflate_m``.

    ``DF(f) - |p - centre(f)|`` is a lower bound of the distance from ``p`` to the
    obstacle cell centres (triangle inequality), so every free planning cell centre
    keeps at least ``inflate_m`` from every occupied cell centre; a blocked one may
    be up to ``2 |p - centre(f)|`` (a world-grid cell diagonal) farther; it is exact when
    planning centres fall on world-grid centres (``cell_m`` an odd multiple of the
    world resolution, e.g. the paper's ``Rgrid = 0.75 m`` on a 0.25 m town grid).
    The map boundary is not an obstacle: it is not inflated.

    Parameters
    ----------
    world_or_grid
        A :class:`World` (its ``grid``) or an :class:`OccupancyGrid`.
    cell_m
        Planning cell edge, the paper's ``Rgrid`` (Table 2: 0.75 m outdoor, 0.25 m
        office).
    inflate_m
        Inflation radius; ``None`` (default) uses ``cell_m``, as the paper does.

    Returns
    -------
    OccupancyGrid
        ``occupied`` = blocked planning cells, ``resolution_m = cell_m``.
    """
    if not cell_m > 0:
        raise ValueError("cell_m must be > 0")
    inflate = float(cell_m if inflate_m is None else inflate_m)
    if inflate < 0:
        raise ValueError("inflate_m must be >= 0")
    grid = _occupancy(world_or_grid)
    if grid is None:
        raise ValueError("the world has no occupancy grid to plan on (free space)")
    shape = tuple(planning_shape(grid.size_m, cell_m).astype(int))
    plan = OccupancyGrid(np.ones(shape, dtype=bool), cell_m, grid.origin_m.copy())
    centres = plan.to_world(np.indices(shape).reshape(grid.dim, -1).T)
    fine = grid.to_cell(centres)
    inside = grid.inside(fine)
    lower = np.full(len(centres), -np.inf)
    offset = np.linalg.norm(centres[inside] - grid.to_world(fine[inside]), axis=1)
    lower[inside] = grid.distance_field_m[tuple(fine[inside].T)] - offset
    plan.occupied = (lower < inflate - _TIE_M).reshape(shape)
    return plan


def _snap(
    plan: OccupancyGrid,
    world_or_grid: World | OccupancyGrid,
    point: np.ndarray,
    allowed: np.ndarray | None = None,
) -> np.ndarray | None:
    """Free planning cell for ``point``: its own cell if free, else the nearest free one.

    Among free cells, the nearest centre whose straight segment from ``point`` is clear
    of obstacles (checked on the 16 nearest) is preferred; failing that, the nearest.
    With ``allowed`` (a mask of cells, e.g. one free component), only those cells are
    candidates and one is returned only if its segment from ``point`` is clear.
    """
    cell = plan.to_cell(point)[0]
    mask = ~plan.occupied if allowed is None else allowed
    if plan.inside(cell[None])[0] and mask[tuple(cell)]:
        return cell
    free_cells = np.argwhere(mask)
    if len(free_cells) == 0:
        return None
    dist = np.linalg.norm(plan.to_world(free_cells) - point, axis=1)
    k = min(16, len(dist))
    cand = np.flatnonzero(dist <= np.partition(dist, k - 1)[k - 1])  # O(V), not a full sort
    order = cand[np.argsort(dist[cand], kind="stable")][:k]  # ties: lowest index first
    near = free_cells[order]
    clear = world_or_grid.segments_clear(
        np.repeat(point[None], len(near), axis=0), plan.to_world(near)
    )
    if clear.any():
        return near[int(np.argmax(clear))]
    return near[0] if allowed is None else None


def _resnap(
    plan: OccupancyGrid,
    world_or_grid: World | OccupancyGrid,
    start: np.ndarray,
    goal: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    connectivity: str,
) -> tuple[np.ndarray, np.ndarray] | None:
    """Start and goal cells in one free component, when their own snaps are apart.

    A point close to a wall may snap into a pocket of free cells cut off by the
    inflation (a corner, a narrow door) while the goal lies in the open: then the
    start (else the goal) is snapped to the nearest cell of the other's component
    that a clear straight segment reaches. A goal truly walled off stays unreachable.
    """
    full = connectivity == "full"
    structure = np.ones((3,) * plan.dim) if full else ndimage.generate_binary_structure(plan.dim, 1)
    labels, _ = ndimage.label(~plan.occupied, structure=structure)
    if labels[tuple(a)] == labels[tuple(b)]:
        return None  # one component already: A* failing is not the snap's doing
    a2 = _snap(plan, world_or_grid, start, allowed=labels == labels[tuple(b)])
    if a2 is not None:
        return a2, b
    b2 = _snap(plan, world_or_grid, goal, allowed=labels == labels[tuple(a)])
    return (a, b2) if b2 is not None else None


def plan_path(
    world_or_grid: World | OccupancyGrid,
    start_m: Sequence[float] | np.ndarray,
    goal_m: Sequence[float] | np.ndarray,
    *,
    cell_m: float,
    inflate_m: float | None = None,
    connectivity: str = "full",
    planning: OccupancyGrid | None = None,
) -> np.ndarray | None:
    """Shortest obstacle-free waypoint path in metres (continuous-connectivity paper, Sec. 3.2).

    Builds the inflated planning grid (:func:`planning_grid`: cells of ``cell_m`` =
    ``Rgrid``, a cell blocked when an obstacle lies within ``inflate_m`` of its
    centre), snaps ``start_m`` and ``goal_m`` to free cells (their own cell when it
    is free, else the nearest free cell, preferring one reachable by a clear straight
    segment), runs :func:`astar_grid` and returns the cell centres framed by the two
    points. When the two snapped cells lie in different free components (a point near a
    wall snapped into a pocket that the inflation cut off), one is snapped again into the
    other's component, if a clear straight segment reaches it. A :class:`World`
    without obstacles gets the straight segment.

    Parameters
    ----------
    world_or_grid
        A :class:`World` or an :class:`OccupancyGrid` (2-D or 3-D).
    start_m, goal_m
        Points in world coordinates (metres).
    cell_m
        The paper's ``Rgrid`` (Table 2: 0.75 m outdoor, 0.25 m office).
    inflate_m
        Inflation radius; ``None`` uses ``cell_m`` (the paper's choice).
    connectivity
        Passed to :func:`astar_grid`.
    planning
        A planning grid from :func:`planning_grid` to reuse (it must have been built
        from this world with this ``cell_m`` and ``inflate_m``); ``None`` builds it.

    Returns
    -------
    numpy.ndarray or None
        ``(k, dim)`` waypoints, ``[start_m, centres..., goal_m]`` (consecutive
        duplicates removed); ``None`` when no free planning cell exists or the goal's
        cell is not reachable from the start's.

    Notes
    -----
    Every interior waypoint keeps at least ``inflate_m`` from the obstacle cell
    centres, so (triangle inequality) every point of the segments between them keeps
    at least ``inflate_m - sqrt(dim) / 2 * cell_m`` (0.10 m for the paper's 3-D
    ``Rgrid = inflate = 0.75 m``); the first and last segments join the free cells to
    the given points, which may be closer to obstacles. Cost: building the grid is
    ``O(V)`` vectorised (plus, once per occupancy grid, its distance field); A* is
    ``O(E log V)``, see :func:`astar_grid`.
    """
    start = np.asarray(start_m, dtype=float).reshape(-1)
    goal = np.asarray(goal_m, dtype=float).reshape(-1)
    grid = _occupancy(world_or_grid)
    dim = grid.dim if grid is not None else world_or_grid.dim
    if len(start) != dim or len(goal) != dim:
        raise ValueError(f"start_m and goal_m need {dim} coordinates")
    if grid is None or not grid.occupied.any():
        # free space: the straight segment is the shortest path
        pts = np.stack([start, goal])
        inside = world_or_grid.in_bounds(pts) if grid is None else grid.inside(grid.to_cell(pts))
        return _dedupe(pts) if inside.all() else None
    plan = planning
    if plan is None:
        plan = planning_grid(world_or_grid, cell_m=cell_m, inflate_m=inflate_m)
    elif plan.dim != dim or not np.isclose(plan.resolution_m, cell_m):
        raise ValueError("planning grid does not match the world's dimension or cell_m")
    a = _snap(plan, world_or_grid, start)
    b = _snap(plan, world_or_grid, goal)
    if a is None or b is None:
        return None
    cells = astar_grid(~plan.occupied, a, b, connectivity=connectivity)
    if cells is None:
        pair = _resnap(plan, world_or_grid, start, goal, a, b, connectivity)
        if pair is None:
            return None
        cells = astar_grid(~plan.occupied, *pair, connectivity=connectivity)
        if cells is None:
            return None
    return _dedupe(np.concatenate([start[None], plan.to_world(cells), goal[None]]))


def _dedupe(pts: np.ndarray) -> np.ndarray:
    """Drop consecutive duplicate points."""
    keep = np.ones(len(pts), dtype=bool)
    keep[1:] = np.any(np.diff(pts, axis=0) != 0.0, axis=1)
    return pts[keep]
