"""The pruning bounds of the compiled exact Steiner tree.

``steiner_kernel`` drops a label ``(S, v)`` when its cost plus ``lower_bounds`` exceeds
the best tree known, so a bound that is too high loses the optimum and one that is too low
only loses speed. Both directions are checked: the bound equals an independent formula
(networkx's MST of the metric closure), and it never exceeds what an optimal tree still
has to spend, by the reference solver.
"""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest

from tether import jit
from tether.recurrent.planning.steiner import steiner_tree

pytestmark = pytest.mark.skipif(not jit.available(), reason="needs numba")


def _instance(seed: int, n: int, k: int) -> tuple[nx.Graph, list[int], np.ndarray]:
    """A connected weighted graph, ``k`` terminals and the distances from each."""
    rng = np.random.default_rng(seed)
    g = nx.connected_watts_strogatz_graph(n, 4, 0.4, seed=seed)
    for u, v in g.edges:
        g.edges[u, v]["weight"] = float(rng.integers(0, 9)) if seed % 2 else rng.uniform(0, 4)
    terminals = [int(t) for t in rng.choice(n, size=k, replace=False)]
    dist = nx.floyd_warshall_numpy(g, nodelist=range(n), weight="weight")
    return g, terminals, dist[terminals]


def _kernel_bounds(dterm: np.ndarray, terminals: list[int], s: int) -> np.ndarray:
    from tether.recurrent.planning.steiner_kernels import lower_bounds

    lb = np.empty(dterm.shape[1])
    lower_bounds(dterm, np.array(terminals, np.int64), s, lb, np.empty((2, len(lb))))
    return lb


def _outside(terminals: list[int], s: int) -> list[int]:
    """Indices into ``terminals`` of the terminals outside subset ``s``, with the root."""
    k = len(terminals) - 1
    return [i for i in range(k) if not (s >> i) & 1] + [k]


@pytest.mark.parametrize("seed", range(8))
def test_lower_bounds_equal_the_farthest_terminal_or_half_a_one_tree(seed: int) -> None:
    """For every subset and vertex: max(farthest outside terminal, (MST + 2 nearest) / 2)."""
    g, terminals, dterm = _instance(seed, n=30, k=6)
    for s in range(1, 1 << (len(terminals) - 1)):
        rest = _outside(terminals, s)
        closure = nx.Graph()
        closure.add_nodes_from(rest)
        closure.add_weighted_edges_from(
            (a, b, dterm[a, terminals[b]]) for a in rest for b in rest if a < b
        )
        mst = nx.minimum_spanning_tree(closure).size(weight="weight")
        near = np.sort(dterm[rest], axis=0)
        expected = near[-1].copy()
        if len(rest) >= 2:
            expected = np.maximum(expected, 0.5 * (mst + near[0] + near[1]))
        np.testing.assert_allclose(_kernel_bounds(dterm, terminals, s), expected, rtol=1e-12)


@pytest.mark.parametrize("seed", range(6))
def test_lower_bounds_never_exceed_the_rest_of_an_optimal_tree(seed: int) -> None:
    """``lb[v]`` <= the optimal Steiner tree of ``v`` and the terminals outside ``S``."""
    g, terminals, dterm = _instance(seed, n=12, k=5)
    for s in range(1, 1 << (len(terminals) - 1)):
        rest = [terminals[i] for i in _outside(terminals, s)]
        lb = _kernel_bounds(dterm, terminals, s)
        with jit.using(False):
            needed = [steiner_tree(g, [*rest, v]).cost for v in g]
        assert np.all(lb <= np.array(needed) + 1e-9)
