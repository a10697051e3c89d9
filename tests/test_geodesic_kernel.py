"""The compiled coarse-grid Dijkstra against scipy's (the reference) and networkx.

Distances must be the same bits, predecessors the same wherever the kernel does not
flag a tie, and every path of :class:`Geodesics` the same as scipy's path.
"""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest
from scipy.sparse.csgraph import connected_components, dijkstra

from tether import jit
from tether.paths.geodesic import CoarseGrid, _trace

pytest.importorskip("numba")


def _maps() -> list[tuple[int, np.ndarray, int]]:
    """Random free masks: sparse and dense obstacles, blobs, coarse factors 1 and 3."""
    out = []
    for seed in range(16):
        rng = np.random.default_rng(seed)
        shape = (int(rng.integers(20, 90)), int(rng.integers(20, 90)))
        p = (0.05, 0.2, 0.35)[seed % 3]
        occ = rng.random(shape) < p
        if seed % 4 == 3:  # a few large square obstacles (symmetric, many ties)
            occ[:] = False
            for _ in range(6):
                x, y = rng.integers(0, shape[0] - 6), rng.integers(0, shape[1] - 6)
                occ[x : x + 5, y : y + 5] = True
        out.append((seed, ~occ, 1 if seed % 2 else 3))
    return out


@pytest.mark.parametrize(("seed", "free", "factor"), _maps())
def test_kernel_matches_scipy(seed: int, free: np.ndarray, factor: int) -> None:
    c = CoarseGrid(free, factor)
    if c.n_nodes == 0:
        return
    rng = np.random.default_rng(seed)
    src = rng.choice(c.n_nodes, size=min(6, c.n_nodes), replace=False)
    # the original call (undirected scan) of the reference
    want_d, want_p = dijkstra(c.graph, directed=False, indices=src, return_predecessors=True)
    with jit.using(False):
        ref_d, ref_p = c.distances(src, predecessors=True)
        ref = c.geodesics(src)
    assert np.array_equal(ref_d, want_d) and np.array_equal(ref_p, want_p)
    assert np.array_equal(ref.pred, want_p) and not ref.tie.any()
    with jit.using(True):
        d = c.distances(src)
        geo = c.geodesics(src)
    assert np.array_equal(d, want_d)  # the same bits
    assert np.array_equal(geo.dist, want_d)
    assert np.array_equal(geo.pred[~geo.tie], want_p[~geo.tie])
    assert geo.pred.dtype == want_p.dtype
    for i in range(len(src)):
        for t in np.flatnonzero(np.isfinite(want_d[i])):
            assert np.array_equal(geo.path(i, int(t)), c.path(want_p[i], int(t)))


def test_ties_resolved_by_scipy() -> None:
    """A mirror-symmetric map: two equal neighbours lead to a cell, the path is scipy's."""
    free = np.ones((7, 7), dtype=bool)
    free[3, 2:4] = False  # from (3, 0), (3, 4) is reached from (2, 4) or (4, 4) alike
    c = CoarseGrid(free, 1)
    src = int(c.node[3, 0])
    target = int(c.node[3, 4])
    _, want = dijkstra(c.graph, directed=False, indices=[src], return_predecessors=True)
    with jit.using(True):
        geo = c.geodesics([src])
    assert geo.tie[0, target]  # the kernel cannot tell which one scipy scanned first
    assert np.array_equal(geo.path(0, target), c.path(want[0], target))
    assert not geo.tie[0].any()  # the row is scipy's now
    assert np.array_equal(geo.pred[0], want[0])


def test_paths_through_ties_on_random_maps() -> None:
    """The tie fallback is exercised (so the comparison above can fail without it)."""
    crossed = 0
    for _, free, factor in _maps():
        c = CoarseGrid(free, factor)
        if c.n_nodes == 0:
            continue
        src = np.arange(0, c.n_nodes, max(1, c.n_nodes // 5))
        with jit.using(True):
            geo = c.geodesics(src)
        for i in range(len(src)):
            for t in np.flatnonzero(np.isfinite(geo.dist[i])):
                crossed += bool(geo.tie[i, _trace(geo.pred[i], int(t))].any())
    assert crossed > 0


@pytest.mark.parametrize(("seed", "free", "factor"), _maps()[:6])
def test_kernel_against_networkx(seed: int, free: np.ndarray, factor: int) -> None:
    """An independent oracle: networkx's Dijkstra on the graph built edge by edge."""
    c = CoarseGrid(free, factor)
    if c.n_nodes == 0:
        return
    g = nx.Graph()
    g.add_nodes_from(range(c.n_nodes))
    t = c.traversable
    for i, (x, y) in enumerate(c.cells):
        for dx, dy in ((1, 0), (0, 1), (1, 1), (1, -1)):
            u, v = x + dx, y + dy
            if 0 <= u < t.shape[0] and 0 <= v < t.shape[1] and t[u, v]:
                if dx and dy and not (t[x + dx, y] and t[x, y + dy]):
                    continue
                g.add_edge(i, int(c.node[u, v]), weight=factor * (np.sqrt(2.0) if dy and dx else 1))
    src = int(np.random.default_rng(seed).integers(c.n_nodes))
    ref = nx.single_source_dijkstra_path_length(g, src)
    with jit.using(True):
        geo = c.geodesics([src])
    want = np.array([ref.get(i, np.inf) for i in range(c.n_nodes)])
    assert np.array_equal(geo.dist[0], want)  # the same smallest sums of the same steps
    for t_ in np.flatnonzero(np.isfinite(want))[::7]:
        path = geo.path(0, int(t_))
        steps = np.linalg.norm(np.diff(path, axis=0), axis=1)
        assert np.isclose(steps.sum(), want[t_], rtol=1e-12, atol=0)
        assert (c.node_at(path) >= 0).all()


@pytest.mark.parametrize(("seed", "free", "factor"), _maps())
def test_components_match_scipy(seed: int, free: np.ndarray, factor: int) -> None:
    c = CoarseGrid(free, factor)
    _, want = connected_components(c.graph, directed=False)
    assert np.array_equal(c.components, want)


@pytest.mark.parametrize(("seed", "free", "factor"), _maps())
def test_lazy_paths_match_scipy(seed: int, free: np.ndarray, factor: int) -> None:
    """Paths traced from the distances alone (``lazy``) are scipy's, for every target.

    Catches a predecessor rule that differs from the eager kernel's (e.g. the first
    candidate instead of the smallest label), a lost tie flag (the fallback not taken)
    or an unreached target traced through.
    """
    c = CoarseGrid(free, factor)
    if c.n_nodes == 0:
        return
    rng = np.random.default_rng(seed)
    src = rng.choice(c.n_nodes, size=min(4, c.n_nodes), replace=False)
    want_d, want_p = dijkstra(c.graph, directed=False, indices=src, return_predecessors=True)
    with jit.using(True):
        lazy = c.geodesics(src, lazy=True)
        eager = c.geodesics(src)
    assert lazy.pred is None and np.array_equal(lazy.dist, want_d)
    for i in range(len(src)):
        for t in range(c.n_nodes):  # unreached targets too: the path is the target alone
            assert np.array_equal(lazy.path(i, t), c.path(want_p[i], t))
            assert np.array_equal(lazy.path(i, t), eager.path(i, t))


def test_lazy_path_through_a_tie() -> None:
    """The mirror-symmetric map: the lazy trace sees the tie and takes scipy's path."""
    from tether.paths.geodesic_kernels import trace_kernel

    free = np.ones((7, 7), dtype=bool)
    free[3, 2:4] = False
    c = CoarseGrid(free, 1)
    src, target = int(c.node[3, 0]), int(c.node[3, 4])
    _, want = dijkstra(c.graph, directed=False, indices=[src], return_predecessors=True)
    with jit.using(True):
        geo = c.geodesics([src], lazy=True)
        assert trace_kernel(*c._kernel_grid(), geo.dist[0], target)[1]  # flagged
        assert np.array_equal(geo.path(0, target), c.path(want[0], target))
