"""Synthetic exploration graphs ``G^t`` for tests and planning benchmarks.

An instance looks like one planning stage of the recurrent-connectivity paper
(Banfi et al., Sec. III and VII): an office-like 2-D map (walls with doors and
clutter), the part explored so far (free cells within a geodesic radius of the
base station), vertices sampled in it, *frontier* vertices on the boundary
between explored and unexplored free space, communication edges by the
limited line-of-sight model (distance <= range and segment clear of
obstacles), and utilities by eq. (1), ``U(f) = g(f) / min_j d(p_j, f)^2`` with
``g`` an information gain (m^2) and ``d`` the travel distance of the closest
robot. The communication range is chosen so that the graph has about the
requested number of edges (the paper's instances: ~200 vertices, ~2,000
edges, 12 robots).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import networkx as nx
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from tether.world.grid import OccupancyGrid

__all__ = ["PlanningInstance", "exploration_instance", "office_grid"]


@dataclass
class PlanningInstance:
    """One planning stage: everything the configuration and deployment planners take.

    Attributes
    ----------
    graph
        ``G^t``: vertices ``0..n-1`` with ``pos`` (m); communication edges with
        ``length_m``.
    base
        The base-station vertex ``b``.
    utilities
        ``U(f)`` for every frontier ``f`` (eq. 1), all > 0.
    robots
        Current vertex of each robot (robot id -> vertex).
    ready
        Ids of the ready robots ``R^t``; ``budget = len(ready)``.
    goals
        Goal vertex of each non-ready robot (robot id -> vertex), i.e. the
        vertices the configuration problem treats as already occupied.
    travel_m
        ``(n, n)`` travel distances between vertices (shortest paths along
        obstacle-free segments), the ``d_ij`` of the paper.
    """

    graph: nx.Graph
    base: int
    utilities: dict[int, float]
    robots: dict[int, int]
    ready: frozenset[int]
    goals: dict[int, int] = field(default_factory=dict)
    travel_m: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))

    @property
    def budget(self) -> int:
        """``|R^t|``, the number of ready robots."""
        return len(self.ready)


def office_grid(
    rng: np.random.Generator, size_m: tuple[float, float] = (80.0, 60.0), resolution_m: float = 1.0
) -> OccupancyGrid:
    """An office-like occupancy grid: a lattice of walls with doors, plus clutter."""
    nx_, ny_ = (int(round(s / resolution_m)) for s in size_m)
    occ = np.zeros((nx_, ny_), dtype=bool)
    occ[[0, -1], :] = True
    occ[:, [0, -1]] = True
    door = max(2, int(round(3.0 / resolution_m)))
    xs = np.sort(rng.choice(np.arange(8, nx_ - 8), size=3, replace=False))
    ys = np.sort(rng.choice(np.arange(8, ny_ - 8), size=2, replace=False))
    for x in xs:
        occ[x, :] = True
        for _ in range(3):
            y0 = int(rng.integers(1, ny_ - door - 1))
            occ[x, y0 : y0 + door] = False
    for y in ys:
        occ[:, y] = True
        for _ in range(4):
            x0 = int(rng.integers(1, nx_ - door - 1))
            occ[x0 : x0 + door, y] = False
    for _ in range(25):  # furniture
        cx, cy = int(rng.integers(2, nx_ - 4)), int(rng.integers(2, ny_ - 4))
        w, h = int(rng.integers(1, 4)), int(rng.integers(1, 4))
        occ[cx : cx + w, cy : cy + h] = True
    return OccupancyGrid(occ, resolution_m)


def _grid_geodesic(grid: OccupancyGrid, sources: np.ndarray) -> np.ndarray:
    """8-connected geodesic distances (m) from source cells to every cell."""
    free = ~grid.occupied
    shape = free.shape
    cells = np.argwhere(free)
    flat_of = np.ravel_multi_index(tuple(cells.T), shape)
    rows, cols, vals = [], [], []
    for dx, dy in ((1, 0), (0, 1), (1, 1), (1, -1)):
        nb = cells + (dx, dy)
        ok = np.all((nb >= 0) & (nb < shape), axis=1)
        ok[ok] = free[tuple(nb[ok].T)]
        rows.append(flat_of[ok])
        cols.append(np.ravel_multi_index(tuple(nb[ok].T), shape))
        vals.append(np.full(int(ok.sum()), np.hypot(dx, dy) * grid.resolution_m))
    mat = sp.csr_matrix(
        (np.concatenate(vals), (np.concatenate(rows), np.concatenate(cols))),
        shape=(free.size, free.size),
    )
    flat = np.ravel_multi_index(tuple(np.atleast_2d(sources).T), shape)
    return dijkstra(mat, directed=False, indices=flat).reshape(len(flat), *shape)


def _spread(rng: np.random.Generator, cells: np.ndarray, k: int, min_sep: float) -> np.ndarray:
    """Up to ``k`` random cells with pairwise separation >= ``min_sep`` (cells)."""
    chosen: list[np.ndarray] = []
    for c in cells[rng.permutation(len(cells))]:
        if all(np.hypot(*(c - d)) >= min_sep for d in chosen):
            chosen.append(c)
            if len(chosen) == k:
                break
    return np.asarray(chosen).reshape(-1, 2)


def exploration_instance(
    seed: int | np.random.Generator = 0,
    *,
    n_vertices: int = 200,
    n_edges: int = 2000,
    n_frontiers: int = 30,
    n_robots: int = 12,
    n_busy: int = 0,
    explored_radius_m: float = 35.0,
) -> PlanningInstance:
    """A random exploration graph shaped like the paper's planning instances.

    Parameters
    ----------
    seed
        Seed or generator; the instance is a deterministic function of it.
    n_vertices, n_edges, n_frontiers
        Target sizes of ``G^t`` (vertices, communication edges, frontiers). The
        result is the base-station component, so it may be slightly smaller.
    n_robots
        Team size ``m``; robots start at random non-frontier vertices.
    n_busy
        How many robots are *not* ready. Their goals form a chain of vertices
        connected to the base (a previous plan still being executed).
    explored_radius_m
        Geodesic radius of the explored region around the base station.
    """
    rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(seed)
    for _ in range(50):  # redraw maps whose explored part is too closed-in
        inst = _draw(rng, n_vertices, n_edges, n_frontiers, n_robots, n_busy, explored_radius_m)
        if (
            inst.graph.number_of_nodes() >= 0.9 * n_vertices
            and len(inst.utilities) >= 0.8 * n_frontiers
        ):
            break
    return inst


def _draw(
    rng: np.random.Generator,
    n_vertices: int,
    n_edges: int,
    n_frontiers: int,
    n_robots: int,
    n_busy: int,
    explored_radius_m: float,
) -> PlanningInstance:
    grid = office_grid(rng)
    free_cells = np.argwhere(~grid.occupied)
    base_cell = free_cells[rng.integers(len(free_cells))]
    geo = _grid_geodesic(grid, base_cell[None])[0]
    explored = np.isfinite(geo) & (geo <= explored_radius_m)
    unexplored_free = ~grid.occupied & ~explored
    near_unexplored = np.zeros_like(explored)
    for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1)):
        near_unexplored |= np.roll(unexplored_free, (dx, dy), axis=(0, 1))
    frontier_cells = np.argwhere(explored & near_unexplored)
    fr = _spread(rng, frontier_cells, n_frontiers, 1.5)
    inner = np.argwhere(explored & ~near_unexplored)
    inner = inner[np.any(inner != base_cell, axis=1)]
    others = _spread(rng, inner, n_vertices - 1 - len(fr), 1.5)
    cells = np.vstack([base_cell[None], others, fr])
    pos = grid.to_world(cells)
    n = len(pos)
    # Limited line of sight: all clear pairs, then the range giving ~n_edges edges.
    ii, jj = np.triu_indices(n, 1)
    clear = grid.segments_clear(pos[ii], pos[jj])
    ii, jj = ii[clear], jj[clear]
    length = np.linalg.norm(pos[ii] - pos[jj], axis=1)
    order = np.argsort(length)[:n_edges]
    full = nx.Graph()
    full.add_nodes_from(range(n))
    full.add_edges_from((int(ii[e]), int(jj[e]), {"length_m": float(length[e])}) for e in order)
    keep = sorted(nx.node_connected_component(full, 0))
    remap = {v: k for k, v in enumerate(keep)}
    g = nx.relabel_nodes(full.subgraph(keep), remap)
    for v in keep:
        g.nodes[remap[v]]["pos"] = pos[v]
    frontier_ids = [remap[v] for v in keep if v >= n - len(fr)]
    n = len(keep)
    # Travel distances d_ij: shortest paths over all clear segments (any length).
    in_keep = np.isin(ii, keep) & np.isin(jj, keep)
    ra = np.array([remap[v] for v in ii[in_keep]], dtype=np.intp)
    rb = np.array([remap[v] for v in jj[in_keep]], dtype=np.intp)
    travel_m = dijkstra(sp.csr_matrix((length[in_keep], (ra, rb)), shape=(n, n)), directed=False)
    # Robots at random non-frontier vertices, goals of busy robots along a chain from b.
    non_frontier = [v for v in range(1, n) if v not in set(frontier_ids)]
    robots = {r: int(v) for r, v in enumerate(rng.choice(non_frontier, n_robots))}
    goals: dict[int, int] = {}
    if n_busy:
        chain = _random_chain(g, 0, n_busy, rng, forbidden=set(frontier_ids))
        goals = {r: v for r, v in zip(range(n_busy), chain, strict=False)}
    ready = frozenset(range(len(goals), n_robots))
    gain = rng.uniform(20.0, 200.0, size=len(frontier_ids))
    utilities = {}
    for f, gf in zip(frontier_ids, gain, strict=True):
        d = min(travel_m[robots[r], f] for r in robots)
        utilities[int(f)] = float(gf / max(d, 1.0) ** 2)
    return PlanningInstance(g, 0, utilities, robots, ready, goals, travel_m)


def _random_chain(
    g: nx.Graph, base: int, k: int, rng: np.random.Generator, forbidden: set[int]
) -> list[int]:
    """``k`` distinct vertices forming a path that starts next to ``base``."""
    chain: list[int] = []
    cur = base
    used = {base}
    for _ in range(k):
        options = [v for v in g.neighbors(cur) if v not in used and v not in forbidden]
        if not options:
            break
        cur = int(rng.choice(sorted(options)))
        chain.append(cur)
        used.add(cur)
    return chain
