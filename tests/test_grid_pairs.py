"""Pairs within range through the cell grid against the k-d tree, exactly.

:mod:`tether.graph.grid_kernels` must return :func:`tether.graph.pairs_within`'s pairs
(same set, same lexicographic order): random teams in 2-D and 3-D, lattices whose
neighbours sit exactly at the range, duplicate points, ranges tiny or huge against
the team.
"""

from __future__ import annotations

import numpy as np
import pytest

from tether import jit
from tether.graph import pairs_within

pytest.importorskip("numba")


def _both(q: np.ndarray, r: float) -> tuple[np.ndarray, np.ndarray]:
    """The grid's pairs (with as many cells as needed) and the k-d tree's."""
    from tether.graph.grid_kernels import CELL_SLACK, pairs_within_grid_kernel

    with jit.using(False):
        ref = pairs_within(q, r)
    ncell = (np.floor(np.ptp(q, axis=0) / (r * CELL_SLACK)) + 1).astype(np.int64)
    return pairs_within_grid_kernel(np.ascontiguousarray(q), r, ncell), ref


def test_grid_shape_refuses_sparse_grids() -> None:
    from tether.graph.grid_kernels import grid_shape

    q = np.array([[0.0, 0.0], [1000.0, 1000.0], [5.0, 5.0]])
    assert grid_shape(q, 1.0) is None  # a million cells for three points: the k-d tree
    assert grid_shape(q, 400.0).tolist() == [3, 3]


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("dim", [2, 3])
def test_grid_pairs_equal_kdtree_pairs(seed: int, dim: int) -> None:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 900))
    q = rng.uniform(-40.0, 40.0 + 5 * n ** (1 / dim), (n, dim))
    for r in (0.5, 3.0, 15.0, 500.0):
        fast, ref = _both(q, r)
        np.testing.assert_array_equal(fast, ref)
        assert fast.dtype == ref.dtype


def test_lattice_at_exact_range_and_duplicates() -> None:
    side = np.arange(30) * 7.0
    q = np.stack(np.meshgrid(side, side), -1).reshape(-1, 2)
    q = np.concatenate([q, q[:40]])  # duplicates: distance 0
    for r in (7.0, 7.0 * np.sqrt(2), 14.0):
        fast, ref = _both(q, r)
        np.testing.assert_array_equal(fast, ref)


def test_pairs_within_uses_the_grid_when_warm() -> None:
    import numba  # noqa: F401 - numba loaded: jit.warm()

    rng = np.random.default_rng(3)
    q = rng.uniform(0.0, 300.0, (2_000, 2))
    with jit.using(False):
        ref = pairs_within(q, 12.0)
    with jit.using(True):
        fast = pairs_within(q, 12.0)
    np.testing.assert_array_equal(fast, ref)
