"""The exploration graph's compiled vertex kernels against the reference (numpy/scipy)."""

from __future__ import annotations

import numpy as np
import pytest

from tether import jit
from tether.paths.geodesic import CoarseGrid
from tether.recurrent.planning.expgraph import _KeySet, frontier_nodes, window_counts
from tether.recurrent.planning.frontiers import frontier_clusters

pytest.importorskip("numba")


def _case(seed: int) -> tuple[np.ndarray, np.ndarray, CoarseGrid, np.ndarray, int, int]:
    rng = np.random.default_rng(seed)
    shape = (int(rng.integers(15, 120)), int(rng.integers(15, 120)))
    occ = rng.random(shape) < (0.05, 0.15, 0.3)[seed % 3]
    known = np.zeros(shape, dtype=bool)  # a few sensed discs, as a robot team leaves them
    xx, yy = np.indices(shape)
    for _ in range(int(rng.integers(1, 6))):
        c = rng.random(2) * shape
        known |= (xx - c[0]) ** 2 + (yy - c[1]) ** 2 < rng.uniform(5, 30) ** 2
    known |= rng.random(shape) < 0.02  # scattered cells: many tiny clusters
    coarse = CoarseGrid(known & ~occ, int(rng.integers(1, 4)))
    allowed = rng.random(coarse.n_nodes) < 0.8
    return known, occ, coarse, allowed, int(rng.integers(1, 6)), int(rng.integers(3, 40))


@pytest.mark.parametrize("seed", range(40))
def test_frontier_nodes_kernel_matches_reference(seed: int) -> None:
    known, occ, coarse, allowed, min_cells, extent = _case(seed)
    with jit.using(False):
        want = frontier_nodes(known, occ, coarse, allowed, min_cells, extent)
    with jit.using(True):
        got = frontier_nodes(known, occ, coarse, allowed, min_cells, extent)
    assert got == want
    assert len(want) == len(frontier_clusters(known, occ, min_cells, extent))


def test_frontier_nodes_sizes_and_order() -> None:
    """Cluster sizes come out by decreasing size (the order the graph's vertices take)."""
    from tether.recurrent.planning.expgraph_kernels import frontier_nodes_kernel

    known, occ, coarse, allowed, min_cells, extent = _case(3)
    _, sizes = frontier_nodes_kernel(known, occ, min_cells, extent, coarse.node, coarse.factor,
                                     allowed)  # fmt: skip
    want = [c.size for c in frontier_clusters(known, occ, min_cells, extent)]
    assert sizes.tolist() == want and want == sorted(want, reverse=True)


@pytest.mark.parametrize("seed", range(8))
def test_window_counts_kernel_matches_reference(seed: int) -> None:
    rng = np.random.default_rng(seed)
    mask = rng.random((57, 43)) < 0.4
    pts = rng.uniform(-5, 60, size=(int(rng.integers(1, 200)), 2))  # some windows off the map
    for h in (0, 1, 7, 50):
        with jit.using(False):
            want = window_counts(mask, pts, h)
        with jit.using(True):
            got = window_counts(mask, pts, h)
        assert np.array_equal(got, want)
        c = np.floor(pts).astype(int)  # brute force
        brute = [
            sum(mask[u, v] for u in range(max(x - h, 0), min(x + h + 1, 57))
                for v in range(max(y - h, 0), min(y + h + 1, 43)))
            for x, y in c
        ]  # fmt: skip
        assert got.tolist() == brute


def test_key_set_membership() -> None:
    rng = np.random.default_rng(0)
    ref: set[int] = set()
    ks = _KeySet()
    for _ in range(30):
        new = rng.integers(0, 500, size=int(rng.integers(0, 20)))
        ks.add(new)
        ref |= set(new.tolist())
        probe = rng.integers(-5, 510, size=50)
        assert ks.contains(probe).tolist() == [int(p) in ref for p in probe]
        assert ks.keys.tolist() == sorted(ref)  # sorted, no duplicates (as np.union1d)
    assert len(ks) == len(ref)
