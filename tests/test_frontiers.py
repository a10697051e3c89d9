"""Frontiers, depth sensor, line of sight, coarse geodesics: against brute-force oracles."""

from __future__ import annotations

import math

import networkx as nx
import numpy as np
import pytest

from tether.paths.geodesic import CoarseGrid
from tether.recurrent.planning.expgraph import window_counts
from tether.recurrent.planning.frontiers import cluster_frontiers, frontier_cells
from tether.sensing.depth import DepthSensor, cast_rays
from tether.sensing.links import DiskLinks, LineOfSightLinks, link_pairs
from tether.world.los import segment_free

SEEDS = range(12)


def random_map(rng: np.random.Generator, shape=(40, 33), p=0.2) -> np.ndarray:
    return rng.random(shape) < p


@pytest.mark.parametrize("seed", SEEDS)
def test_frontier_cells_brute_force(seed: int) -> None:
    rng = np.random.default_rng(seed)
    occ = random_map(rng)
    known = rng.random(occ.shape) < 0.5
    got = frontier_cells(known, occ)
    nx_, ny_ = occ.shape
    want = np.zeros_like(got)
    for x in range(nx_):
        for y in range(ny_):
            if not known[x, y] or occ[x, y]:
                continue
            for dx, dy in ((1, 0), (-1, 0), (0, 1), (0, -1)):
                u, v = x + dx, y + dy
                if 0 <= u < nx_ and 0 <= v < ny_ and not known[u, v]:
                    want[x, y] = True
    assert np.array_equal(got, want)


@pytest.mark.parametrize("seed", SEEDS)
def test_clusters_partition_components(seed: int) -> None:
    rng = np.random.default_rng(seed)
    mask = rng.random((50, 45)) < 0.3
    min_cells, extent = 3, 7
    clusters = cluster_frontiers(mask, min_cells=min_cells, max_extent_cells=extent)
    # oracle: 8-connected components with networkx
    g = nx.Graph()
    cells = [tuple(c) for c in np.argwhere(mask)]
    g.add_nodes_from(cells)
    for x, y in cells:
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                if (dx or dy) and (x + dx, y + dy) in g:
                    g.add_edge((x, y), (x + dx, y + dy))
    comp = {c: k for k, cc in enumerate(nx.connected_components(g)) for c in cc}
    seen: set = set()
    for cl in clusters:
        members = {tuple(c) for c in cl.cells}
        assert len(members) == cl.size >= min_cells
        assert not members & seen  # disjoint
        seen |= members
        assert len({comp[c] for c in members}) == 1  # inside one component
        assert len({(x // extent, y // extent) for x, y in members}) == 1  # one tile
    assert seen <= set(cells)
    # every dropped cell belongs to a (component, tile) piece smaller than min_cells
    pieces: dict = {}
    for c in cells:
        pieces.setdefault((comp[c], c[0] // extent, c[1] // extent), []).append(c)
    for c in set(cells) - seen:
        assert len(pieces[(comp[c], c[0] // extent, c[1] // extent)]) < min_cells


def _ray_oracle(occ, origin, angle, rng_cells, step=0.5):
    out = set()
    nx_, ny_ = occ.shape
    for k in range(int(math.floor(rng_cells / step + 1e-9)) + 1):
        s = k * step
        x = origin[0] + s * math.cos(angle)
        y = origin[1] + s * math.sin(angle)
        ix, iy = math.floor(x), math.floor(y)
        if not (0 <= ix < nx_ and 0 <= iy < ny_):
            break
        out.add(ix * ny_ + iy)
        if occ[ix, iy]:
            break
    return out


@pytest.mark.parametrize("seed", SEEDS)
def test_cast_rays_matches_per_ray_oracle(seed: int) -> None:
    rng = np.random.default_rng(seed)
    occ = random_map(rng, (30, 26), 0.1)
    free = np.argwhere(~occ)
    origins = free[rng.choice(len(free), 3)] + rng.random((3, 2))
    heads = rng.uniform(-np.pi, np.pi, 3)
    fov, res, rng_cells = np.radians(60), np.radians(5), 12.0
    got = cast_rays(occ, origins, heads, fov, rng_cells, res)
    for k in range(3):
        want = set()
        for a in np.linspace(-fov / 2, fov / 2, 13):
            want |= _ray_oracle(occ, origins[k], heads[k] + a, rng_cells)
        assert set(got[k].tolist()) == want


def test_sensor_full_rotation_sees_more_and_respects_range() -> None:
    rng = np.random.default_rng(3)
    occ = random_map(rng, (120, 120), 0.02)
    occ[60, 60] = False
    s = DepthSensor(fov_deg=60, range_cells=20, resolution_deg=1)
    fan, full = s.scan(occ, np.array([[60.5, 60.5]] * 2), np.array([0.3, 0.3]), [False, True])
    assert set(fan.tolist()) <= set(full.tolist())
    cells = np.stack(np.divmod(full, occ.shape[1]), axis=1) + 0.5
    assert np.linalg.norm(cells - 60.5, axis=1).max() <= 20 + np.sqrt(2)


@pytest.mark.parametrize("seed", SEEDS)
def test_segment_free_symmetric_and_oracle(seed: int) -> None:
    rng = np.random.default_rng(seed)
    occ = random_map(rng, (40, 40), 0.05)
    a = rng.random((60, 2)) * 40
    b = rng.random((60, 2)) * 40
    ab = segment_free(~occ, a, b)
    assert np.array_equal(ab, segment_free(~occ, b, a))
    # independent of the batch it is evaluated in
    single = np.array([segment_free(~occ, a[i : i + 1], b[i : i + 1])[0] for i in range(60)])
    assert np.array_equal(ab, single)
    # a dense oracle: blocked segments really touch an occupied cell
    for i in np.flatnonzero(~ab):
        t = np.linspace(0, 1, 2000)
        pts = np.floor(a[i] + t[:, None] * (b[i] - a[i])).astype(int)
        assert occ[pts[:, 0], pts[:, 1]].any()


def test_link_models_registry_and_range() -> None:
    from tether.registry import LINK_MODELS

    assert LINK_MODELS.get("los") is LineOfSightLinks
    assert LINK_MODELS.get("disk") is DiskLinks
    free = np.ones((100, 10), dtype=bool)
    pts = np.array([[1.5, 5.5], [50.5, 5.5], [99.5, 5.5]])
    pairs = link_pairs(LineOfSightLinks(range_cells=60), free, pts)
    assert sorted(map(tuple, pairs.tolist())) == [(0, 1), (1, 2)]
    free[30, :] = False  # a wall
    pairs = link_pairs(LineOfSightLinks(range_cells=60), free, pts)
    assert sorted(map(tuple, pairs.tolist())) == [(1, 2)]
    pairs = link_pairs(DiskLinks(range_cells=60), free, pts)
    assert sorted(map(tuple, pairs.tolist())) == [(0, 1), (1, 2)]


@pytest.mark.parametrize("seed", SEEDS)
def test_coarse_geodesic_matches_networkx(seed: int) -> None:
    rng = np.random.default_rng(seed)
    m = rng.random((31, 28)) > 0.15
    c = CoarseGrid(m, 3)
    assert np.array_equal(c.traversable, m[:30, :27].reshape(10, 3, 9, 3).all(axis=(1, 3)))
    if c.n_nodes == 0:
        return
    g = nx.Graph()
    g.add_nodes_from(range(c.n_nodes))
    t = c.traversable
    for i, (x, y) in enumerate(c.cells):
        for dx in (-1, 0, 1):
            for dy in (-1, 0, 1):
                u, v = x + dx, y + dy
                if (dx or dy) and 0 <= u < t.shape[0] and 0 <= v < t.shape[1] and t[u, v]:
                    if dx and dy and not (t[x + dx, y] and t[x, y + dy]):
                        continue
                    g.add_edge(i, int(c.node[u, v]), weight=3 * math.hypot(dx, dy))
    src = int(rng.integers(c.n_nodes))
    d, pred = c.distances([src], predecessors=True)
    ref = nx.single_source_dijkstra_path_length(g, src)
    want = np.array([ref.get(i, np.inf) for i in range(c.n_nodes)])
    assert np.allclose(d[0], want)
    # a reconstructed path has the reported length and only traversable cells
    reach = np.flatnonzero(np.isfinite(d[0]))
    dst = int(reach[-1])
    path = c.path(pred[0], dst)
    assert np.isclose(np.linalg.norm(np.diff(path, axis=0), axis=1).sum(), d[0, dst])
    assert (c.node_at(path) >= 0).all()


@pytest.mark.parametrize("seed", range(6))
def test_window_counts_both_paths(seed: int) -> None:
    rng = np.random.default_rng(seed)
    mask = rng.random((37, 41)) < 0.4
    for n_pts, h in ((3, 2), (80, 9)):  # direct sums and integral image
        pts = rng.random((n_pts, 2)) * [37, 41]
        got = window_counts(mask, pts, h)
        c = np.floor(pts).astype(int)
        want = [mask[max(x - h, 0) : x + h + 1, max(y - h, 0) : y + h + 1].sum() for x, y in c]
        assert np.array_equal(got, want)
