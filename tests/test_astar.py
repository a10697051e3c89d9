"""A* on grids and metric planning (continuous-connectivity paper, Sec. 3.2).

Oracles: scipy's Dijkstra on the same lattice graph built here independently (costs),
a k-d tree of the obstacle cell centres (inflation), and direct checks of the path's
cells (free, neighbours, ends).
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra
from scipy.spatial import cKDTree

from tether.paths.astar import astar_grid, neighbour_offsets, plan_path, planning_grid
from tether.world.grid import OccupancyGrid
from tether.world.world import World


def lattice_graph(free: np.ndarray, connectivity: str) -> sp.csr_matrix:
    """The move graph of free cells, from an explicit enumeration of steps (the oracle)."""
    dim = free.ndim
    steps = [
        s
        for s in itertools.product((-1, 0, 1), repeat=dim)
        if any(s) and (connectivity == "full" or sum(map(abs, s)) == 1)
    ]
    index = np.arange(free.size).reshape(free.shape)
    cells = np.argwhere(free)
    rows, cols, vals = [], [], []
    for step in steps:
        nb = cells + np.asarray(step)
        ok = np.all((nb >= 0) & (nb < free.shape), axis=1)
        a, b = cells[ok], nb[ok]
        ok2 = free[tuple(b.T)]
        rows.append(index[tuple(a[ok2].T)])
        cols.append(index[tuple(b[ok2].T)])
        vals.append(np.full(int(ok2.sum()), math.sqrt(sum(v * v for v in step))))
    n = free.size
    return sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))), shape=(n, n)
    )


def path_cost(cells: np.ndarray) -> float:
    return float(np.linalg.norm(np.diff(cells, axis=0), axis=1).sum())


def random_free(rng: np.random.Generator, shape: tuple[int, ...], density: float) -> np.ndarray:
    return rng.random(shape) >= density


def check_path(free, cells, start, goal, connectivity):
    assert np.array_equal(cells[0], start) and np.array_equal(cells[-1], goal)
    assert free[tuple(cells.T)].all(), "path crosses a blocked cell"
    step = np.abs(np.diff(cells, axis=0))
    assert np.all(step.max(axis=1) == 1), "consecutive cells are not neighbours"
    if connectivity == "face":
        assert np.all(step.sum(axis=1) == 1)


CASES = [(2, (18, 15), d) for d in (0.1, 0.3, 0.45, 0.55)] + [
    (3, (9, 8, 7), d) for d in (0.1, 0.3, 0.5, 0.7)
]


@pytest.mark.parametrize("connectivity", ["full", "face"])
@pytest.mark.parametrize(("dim", "shape", "density"), CASES)
def test_cost_equals_dijkstra(dim, shape, density, connectivity):
    rng = np.random.default_rng(1000 * dim + int(100 * density) + (connectivity == "face"))
    n_checked = n_unreachable = 0
    for _ in range(12):
        free = random_free(rng, shape, density)
        cells = np.argwhere(free)
        if len(cells) < 2:
            continue
        graph = lattice_graph(free, connectivity)
        index = np.arange(free.size).reshape(shape)
        for _ in range(4):
            start, goal = cells[rng.choice(len(cells), 2, replace=False)]
            dist = dijkstra(graph, indices=index[tuple(start)])[index[tuple(goal)]]
            for heuristic in ("octile", "euclidean"):
                path = astar_grid(free, start, goal, connectivity=connectivity, heuristic=heuristic)
                if np.isinf(dist):
                    assert path is None
                    n_unreachable += 1
                    continue
                assert path is not None
                check_path(free, path, start, goal, connectivity)
                assert path_cost(path) == pytest.approx(dist, rel=1e-12, abs=1e-12)
                n_checked += 1
    assert n_checked >= 10  # the random grids exercise the search, not only trivial cases
    if density >= 0.55:
        assert n_unreachable > 0  # ... and the unreachable answer


def test_octile_heuristic_is_the_free_lattice_distance():
    # admissible and tight: on an empty grid A*'s cost is the heuristic at the start
    from tether.paths.astar import _heuristic

    for dim, shape in ((2, (9, 7)), (3, (6, 5, 4))):
        free = np.ones(shape, dtype=bool)
        graph = lattice_graph(free, "full")
        dist = dijkstra(graph, indices=0)
        cells = np.argwhere(free)
        h = _heuristic(cells - cells[0], "full", "octile")
        np.testing.assert_allclose(h, dist, rtol=1e-12)
        # consistency: |h(a) - h(b)| <= step cost for every move (h to any goal cell)
        for off in neighbour_offsets(dim):
            a = _heuristic(cells, "full", "octile")
            b = _heuristic(cells + off, "full", "octile")
            assert np.all(np.abs(a - b) <= np.linalg.norm(off) + 1e-12)


def test_unreachable_blocked_and_outside():
    free = np.ones((10, 10, 5), dtype=bool)
    free[:, 5, :] = False  # a wall across the whole grid
    assert astar_grid(free, (0, 0, 0), (9, 9, 4)) is None
    free[9, 5, 4] = True  # one hole in a corner: reachable (diagonal through the hole)
    path = astar_grid(free, (0, 0, 0), (0, 9, 0))
    assert path is not None and any(np.array_equal(c, (9, 5, 4)) for c in path)
    assert astar_grid(free, (0, 0, 0), (0, 5, 0)) is None  # goal blocked
    assert astar_grid(free, (0, 5, 0), (0, 0, 0)) is None  # start blocked
    assert astar_grid(free, (0, 0, 0), (10, 0, 0)) is None  # goal outside
    assert astar_grid(free, (-1, 0, 0), (1, 0, 0)) is None  # start outside
    # a diagonal gap is passable with full connectivity only
    free2 = np.ones((2, 2), dtype=bool)
    free2[0, 1] = free2[1, 0] = False
    assert astar_grid(free2, (0, 0), (1, 1)) is not None
    assert astar_grid(free2, (0, 0), (1, 1), connectivity="face") is None


def test_start_equals_goal_and_determinism():
    free = np.ones((6, 6), dtype=bool)
    assert np.array_equal(astar_grid(free, (2, 3), (2, 3)), [[2, 3]])
    rng = np.random.default_rng(5)
    grid = random_free(rng, (30, 30, 6), 0.25)
    grid[0, 0, 0] = grid[29, 29, 5] = True
    paths = [astar_grid(grid.copy(), (0, 0, 0), (29, 29, 5)) for _ in range(3)]
    assert paths[0] is not None
    assert all(np.array_equal(paths[0], p) for p in paths[1:])


def test_bad_arguments():
    with pytest.raises(ValueError):
        astar_grid(np.ones(5, dtype=bool), (0,), (4,))
    with pytest.raises(ValueError):
        astar_grid(np.ones((3, 3), dtype=bool), (0, 0), (2, 2), connectivity="edge")
    with pytest.raises(ValueError):
        astar_grid(np.ones((3, 3), dtype=bool), (0, 0), (2, 2), heuristic="manhattan")
    with pytest.raises(ValueError):
        astar_grid(np.ones((3, 3), dtype=bool), (0, 0, 0), (2, 2))
    assert len(neighbour_offsets(3)) == 26 and len(neighbour_offsets(2)) == 8
    assert len(neighbour_offsets(3, "face")) == 6 and len(neighbour_offsets(2, "face")) == 4


# ------------------------------------------------------------------ metric planning


def box_grid(rng, shape, resolution_m, n_boxes, dim) -> OccupancyGrid:
    occ = np.zeros(shape, dtype=bool)
    for _ in range(n_boxes):
        lo = rng.integers(0, np.asarray(shape) - 2)
        size = rng.integers(2, np.maximum(np.asarray(shape) // 4, 3))
        occ[tuple(slice(a, a + s) for a, s in zip(lo, size, strict=True))] = True
    return OccupancyGrid(occ, resolution_m, rng.uniform(-5, 5, size=dim))


def obstacle_distance(grid: OccupancyGrid, pts: np.ndarray) -> np.ndarray:
    """Distance from points to the nearest occupied cell centre (k-d tree oracle)."""
    return cKDTree(grid.obstacle_points()).query(pts)[0]


@pytest.mark.parametrize(("ratio", "exact"), [(3, True), (5, True), (2.6, False)])
@pytest.mark.parametrize("dim", [2, 3])
def test_planning_grid_inflation(dim, ratio, exact):
    rng = np.random.default_rng(7 + dim + int(10 * ratio))
    shape = (40, 36) if dim == 2 else (30, 27, 12)
    grid = box_grid(rng, shape, 0.2, 8, dim)
    cell = 0.2 * ratio
    for inflate in (cell, 0.5 * cell, 1.7 * cell):
        plan = planning_grid(grid, cell_m=cell, inflate_m=inflate)
        centres = plan.to_world(np.indices(plan.shape).reshape(dim, -1).T)
        dist = obstacle_distance(grid, centres).reshape(plan.shape)
        outside = ~grid.inside(grid.to_cell(centres)).reshape(plan.shape)
        should_block = (dist < inflate - 1e-9) | outside
        assert np.all(plan.occupied[should_block]), "a cell near an obstacle is free"
        if exact:  # planning centres on fine centres: the rule is exact
            np.testing.assert_array_equal(plan.occupied, should_block)
        else:  # conservative, by at most twice the centre offset (a fine cell diagonal)
            slack = math.sqrt(dim) * 0.2
            assert not np.any(plan.occupied & ~outside & (dist >= inflate + slack))


def endpoints_with_clearance(rng, grid, clearance_m, n):
    free = np.argwhere(grid.distance_field_m >= clearance_m)
    return grid.to_world(free[rng.choice(len(free), size=n, replace=False)])


@pytest.mark.parametrize("dim", [2, 3])
def test_plan_path_keeps_the_inflation(dim):
    rng = np.random.default_rng(11 + dim)
    shape = (60, 50) if dim == 2 else (40, 36, 10)
    n_paths = 0
    for _ in range(4):
        grid = box_grid(rng, shape, 0.25, 10 if dim == 2 else 14, dim)
        world = World(dim=dim, grid=grid)
        cell = 0.75
        plan = planning_grid(world, cell_m=cell)
        pts = endpoints_with_clearance(rng, grid, 2.0, 10)
        for a, b in zip(pts[::2], pts[1::2], strict=True):
            path = plan_path(world, a, b, cell_m=cell, planning=plan)
            if path is None:
                # only if the planning grid really separates the two cells
                ca, cb = plan.to_cell(a)[0], plan.to_cell(b)[0]
                assert astar_grid(~plan.occupied, ca, cb) is None
                continue
            n_paths += 1
            np.testing.assert_array_equal(path[0], a)
            np.testing.assert_array_equal(path[-1], b)
            inner = path[1:-1]
            assert np.all(obstacle_distance(grid, inner) >= cell - 1e-9)
            steps = np.linalg.norm(np.diff(inner, axis=0), axis=1)
            assert np.all(steps <= math.sqrt(dim) * cell + 1e-9)  # grid neighbours
            t = np.linspace(0.0, 1.0, 21)[:, None, None]
            seg = (inner[:-1] + t * (inner[1:] - inner[:-1])).reshape(-1, dim)
            bound = cell - math.sqrt(dim) / 2 * cell  # documented segment clearance
            assert np.all(obstacle_distance(grid, seg) >= bound - 1e-9)
            # same result without the reused planning grid
            np.testing.assert_array_equal(path, plan_path(world, a, b, cell_m=cell))
    assert n_paths >= 10


def test_plan_path_cost_is_optimal_on_the_planning_grid():
    rng = np.random.default_rng(3)
    grid = box_grid(rng, (60, 60), 0.25, 12, 2)
    plan = planning_grid(grid, cell_m=0.75)
    graph = lattice_graph(~plan.occupied, "full")
    index = np.arange(plan.occupied.size).reshape(plan.shape)
    pts = endpoints_with_clearance(rng, grid, 1.5, 8)
    for a, b in zip(pts[::2], pts[1::2], strict=True):
        path = plan_path(grid, a, b, cell_m=0.75)
        ca, cb = plan.to_cell(a)[0], plan.to_cell(b)[0]
        dist = dijkstra(graph, indices=index[tuple(ca)])[index[tuple(cb)]]
        if np.isinf(dist):
            assert path is None
            continue
        inner_len = np.linalg.norm(np.diff(path[1:-1], axis=0), axis=1).sum()
        assert inner_len == pytest.approx(0.75 * dist, rel=1e-12)


def test_plan_path_snaps_and_reports_unreachable():
    occ = np.zeros((40, 40), dtype=bool)
    occ[:, 20:22] = True  # a wall across the map
    grid = OccupancyGrid(occ, 0.25)
    assert plan_path(grid, [1.0, 1.0], [1.0, 9.0], cell_m=0.75) is None
    occ[36:, 20:22] = False  # a 1 m gap near x = 9.5
    grid = OccupancyGrid(occ, 0.25)
    # 1 m gap: closed by a 0.75 m inflation, open with 0.3 m
    assert plan_path(grid, [1.0, 1.0], [1.0, 9.0], cell_m=0.75) is None
    path = plan_path(grid, [1.0, 1.0], [1.0, 9.0], cell_m=0.5, inflate_m=0.3)
    assert path is not None and path[:, 0].max() > 9.0
    # a start inside the inflation (0.3 m from the wall) is snapped to a free cell
    path = plan_path(grid, [2.0, 4.7], [2.0, 1.0], cell_m=0.75)
    assert path is not None and np.array_equal(path[0], [2.0, 4.7])
    assert obstacle_distance(grid, path[1:2])[0] >= 0.75
    # no free planning cell at all
    assert (
        plan_path(OccupancyGrid(np.ones((8, 8), bool), 0.25), [1, 1], [1.5, 1.5], cell_m=0.5)
        is None
    )


def test_plan_path_free_space_is_the_straight_segment():
    world = World(dim=3, bounds_m=np.array([[0, 0, 0], [10, 10, 5]]))
    path = plan_path(world, [1, 1, 1], [9, 8, 2], cell_m=0.75)
    np.testing.assert_array_equal(path, [[1, 1, 1], [9, 8, 2]])
    assert plan_path(world, [1, 1, 1], [11, 8, 2], cell_m=0.75) is None
    empty = OccupancyGrid(np.zeros((10, 10), bool), 1.0)
    np.testing.assert_array_equal(plan_path(empty, [1, 1], [9, 2], cell_m=1.0), [[1, 1], [9, 2]])


def test_plan_path_on_the_town():
    from tether.world import make_scene

    world = make_scene("town", 0, resolution_m=0.25)
    grid = world.grid
    start, goal = np.array([2.0, 2.0, 1.0]), np.array([47.0, 67.0, 1.0])
    path = plan_path(world, start, goal, cell_m=0.75)
    assert path is not None
    assert np.all(obstacle_distance(grid, path[1:-1]) >= 0.75 - 1e-9)
    straight = np.linalg.norm(goal - start)
    length = np.linalg.norm(np.diff(path, axis=0), axis=1).sum()
    assert straight <= length < 1.3 * straight


def test_a_start_in_a_pocket_cut_off_by_the_inflation_is_snapped_out():
    """A robot close to walls may sit in free cells that the inflation isolates (a
    bottle-shaped alcove with a narrow mouth): it must still get a path out through the
    open mouth, while an alcove with its mouth walled stays unreachable."""
    occ = np.zeros((60, 60), dtype=bool)  # 6 m x 6 m at 0.1 m
    occ[20:32, 20:22] = True  # left wall, x 2.0-2.2
    occ[20:32, 31:33] = True  # right wall, x 3.1-3.3
    occ[31:33, 20:33] = True  # top wall, y 3.1-3.3  (rows are y)
    occ[20:22, 20:24] = True  # bottom wall left of the mouth, x 2.0-2.4
    occ[20:22, 28:33] = True  # bottom wall right of the mouth, x 2.8-3.3
    grid = OccupancyGrid(occ.T.copy(), 0.1)  # axis 0 = x
    start, goal = np.array([2.65, 2.65]), np.array([5.0, 0.5])
    plan = planning_grid(grid, cell_m=0.5, inflate_m=0.3)
    own = plan.to_cell(start[None])[0]
    assert not plan.occupied[tuple(own)]  # the start's own cell is free...
    assert astar_grid(~plan.occupied, own, plan.to_cell(goal[None])[0]) is None  # ...but cut off
    path = plan_path(grid, start, goal, cell_m=0.5, inflate_m=0.3)
    assert path is not None
    np.testing.assert_array_equal(path[0], start)
    np.testing.assert_array_equal(path[-1], goal)
    assert grid.segments_clear(path[:-1], path[1:]).all()  # out through the mouth
    occ[20:22, 24:28] = True  # wall the mouth: the alcove is sealed
    sealed = OccupancyGrid(occ.T.copy(), 0.1)
    assert plan_path(sealed, start, goal, cell_m=0.5, inflate_m=0.3) is None
