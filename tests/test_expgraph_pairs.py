"""Candidate link pairs of the exploration graph: one distance matrix = the pairwise gather.

:func:`tether.recurrent.planning.expgraph.pairs_in_range` must give the pairs that
``np.triu_indices`` + ``np.linalg.norm`` give (the formulation it replaced), in the
same order, including pairs exactly at the range.
"""

from __future__ import annotations

import numpy as np
import pytest

from tether.recurrent.planning.expgraph import pairs_in_range


def _reference(positions: np.ndarray, range_cells: float) -> tuple[np.ndarray, np.ndarray]:
    i, j = np.triu_indices(len(positions), k=1)
    close = np.linalg.norm(positions[i] - positions[j], axis=1) <= range_cells
    return i[close], j[close]


@pytest.mark.parametrize("seed", range(12))
def test_pairs_in_range_equal_the_pairwise_norms(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(0, 120))
    if seed % 2:  # coarse cell centres on a lattice: many pairs exactly at the range
        positions = (rng.integers(0, 40, size=(n, 2)) + 0.5) * 3.0
        range_cells = 15.0
    else:
        positions = rng.uniform(0, 300, size=(n, 2))
        range_cells = float(rng.uniform(20, 150))
    got, want = pairs_in_range(positions, range_cells), _reference(positions, range_cells)
    assert all(np.array_equal(g, w) for g, w in zip(got, want, strict=True))
    if seed % 2 and n > 20:  # the boundary is exercised
        d = np.linalg.norm(positions[want[0]] - positions[want[1]], axis=1)
        assert (d == range_cells).any()
