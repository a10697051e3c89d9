"""``ExplorationGraph.vertices_of_nodes`` = ``vertex_of_node`` node by node."""

from __future__ import annotations

import numpy as np
import pytest

from tether.paths.geodesic import CoarseGrid
from tether.recurrent.planning.expgraph import ExplorationGraph


@pytest.mark.parametrize("seed", range(8))
def test_vertices_of_nodes_equal_one_lookup_per_node(seed: int) -> None:
    """Nodes with a vertex, nodes without, ``-1`` (a point off the grid), repeats, and a
    graph with no vertex; catches a lookup in sorted order returned unsorted."""
    rng = np.random.default_rng(seed)
    coarse = CoarseGrid(np.ones((30, 30), dtype=bool), 3)
    v = int(rng.integers(0, 40)) if seed else 0
    nodes = rng.choice(coarse.n_nodes, size=v, replace=False)
    graph = ExplorationGraph(
        np.zeros((v, 2)), nodes, np.zeros(v, int), np.zeros(v), np.empty((0, 2), int), coarse
    )
    asked = np.concatenate([rng.integers(-1, coarse.n_nodes, size=50), nodes[:5], nodes[:3]])
    want = [graph.vertex_of_node(int(n)) for n in asked]
    assert graph.vertices_of_nodes(asked).tolist() == want
