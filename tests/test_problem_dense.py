"""``problem.build(method="dense")`` against the sparse reference: the same problem exactly.

Every field is compared (labels in order, the CSR adjacency entry for entry, hop
distances, predecessors, utilities, fixed vertices), on random graphs from sparse to
dense (scipy switches to Floyd-Warshall above a quarter of the entries), with
non-integer labels, non-ready goals linked to the base or cut off from it, and on the
paper-shaped exploration instances. Plausible bugs this catches: a relay component
taken as "every fixed vertex", the base not first, an off-by-one in the ball or in the
root-frontier reduction, a search stopped one level early, predecessors that differ
between the directed and undirected scans.
"""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest

from tether.recurrent.planning import problem as _problem
from tether.recurrent.planning.synthetic import exploration_instance


def _same(a: _problem.Problem, b: _problem.Problem) -> None:
    assert a.labels == b.labels
    assert a.adj.shape == b.adj.shape and a.adj.dtype == b.adj.dtype
    assert np.array_equal(a.adj.indptr, b.adj.indptr)
    assert np.array_equal(a.adj.indices, b.adj.indices)
    assert np.array_equal(a.adj.data, b.adj.data)
    assert a.dist.dtype == b.dist.dtype and np.array_equal(a.dist, b.dist)
    assert np.array_equal(a.pred, b.pred)
    assert np.array_equal(a.utility, b.utility)
    assert a.budget == b.budget and a.fixed == b.fixed


def _random_case(seed: int) -> tuple[nx.Graph, object, dict, int, list]:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 60))
    p = float(rng.choice([0.04, 0.1, 0.3, 0.7]))
    g = nx.gnp_random_graph(n, p, seed=seed)
    if seed % 3 == 0:  # labels that are not the indices, in a shuffled order
        order = rng.permutation(n)
        g = nx.relabel_nodes(g, {v: f"v{int(order[v])}" for v in g})
    nodes = list(g)
    base = nodes[int(rng.integers(0, n))]
    others = [v for v in nodes if v != base]
    k = int(rng.integers(0, len(others) + 1))
    picks = [others[i] for i in rng.permutation(len(others))[:k]]
    utilities = {v: float(rng.choice([0.0, rng.uniform(0.1, 5.0), 2.0])) for v in picks}
    fixed: list = []
    if seed % 2 and others:  # a chain from the base plus a goal anywhere (maybe cut off)
        cur = base
        for _ in range(int(rng.integers(1, 4))):
            options = sorted(set(g.neighbors(cur)) - {base, *fixed}, key=str)
            if not options:
                break
            cur = options[int(rng.integers(0, len(options)))]
            fixed.append(cur)
        fixed.append(others[int(rng.integers(0, len(others)))])
    return g, base, utilities, int(rng.integers(0, 9)), fixed


@pytest.mark.parametrize("seed", range(120))
def test_dense_build_matches_sparse(seed: int) -> None:
    g, base, utilities, budget, fixed = _random_case(seed)
    ref = _problem.build(g, base, utilities, budget, fixed, method="sparse")
    _same(_problem.build(g, base, utilities, budget, fixed, method="dense"), ref)
    _same(_problem.build(g, base, utilities, budget, fixed), ref)  # auto


@pytest.mark.parametrize("seed", range(4))
def test_dense_build_on_exploration_instances(seed: int) -> None:
    inst = exploration_instance(seed, n_busy=seed % 3)
    for budget in (1, 4, 12):
        args = (inst.graph, inst.base, inst.utilities, budget, list(inst.goals.values()))
        _same(
            _problem.build(*args, method="dense"),
            _problem.build(*args, method="sparse"),
        )


def test_unknown_method() -> None:
    with pytest.raises(ValueError, match="method"):
        _problem.build(nx.path_graph(3), 0, {2: 1.0}, 2, method="fast")
