"""``tether.graph.components`` on small graphs (union-find) = scipy's labels.

Up to ``SMALL_COMPONENTS_N`` nodes the labels come from a union-find; they must be
``scipy.sparse.csgraph.connected_components``' (the reference, used above that size)
number for number, dtype included: callers group robots by label order.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.sparse.csgraph import connected_components

from tether.graph import structure
from tether.graph.structure import adjacency, components


@pytest.mark.parametrize("seed", range(40))
def test_small_graph_labels_are_scipys(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, structure.SMALL_COMPONENTS_N + 1))
    m = int(rng.integers(0, 2 * n))
    pairs = rng.integers(0, n, size=(m, 2))  # repeats, both orders, self-loops
    count, labels = components(n, pairs)
    want_count, want = connected_components(adjacency(n, pairs), directed=False)
    assert count == want_count
    assert labels.dtype == want.dtype and np.array_equal(labels, want)


def test_out_of_range_pairs_still_fail_as_before() -> None:
    with pytest.raises(ValueError):
        components(3, np.array([[0, 3]]))
    with pytest.raises(ValueError):
        components(3, np.array([[-1, 2]]))
