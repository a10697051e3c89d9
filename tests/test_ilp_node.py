"""The node-separator ILP (:mod:`tether.recurrent.planning.ilp_node`) is exact.

Against an enumeration of every connected configuration on random graphs larger than
those of ``test_configuration.py`` (14-20 vertices, budgets up to 6, dense and sparse,
with non-ready robots), against the arc model of the paper's eq. (4)
(:mod:`tether.recurrent.planning.ilp_model`) on exploration graphs, both backends;
its separation finds the same cuts with and without the compiled max-flow.
"""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest

from tether import jit
from tether.recurrent.planning import ilp
from tether.recurrent.planning import problem as _problem
from tether.recurrent.planning.configuration import check_configuration, optimal_configuration
from tether.recurrent.planning.ilp_model import reduce_dominated
from tether.recurrent.planning.ilp_node import NodeSeparatorModel
from tether.recurrent.planning.synthetic import exploration_instance


def connected_best(g: nx.Graph, base, utilities: dict, budget: int, fixed=()) -> float:
    """Best utility over all ``Q`` with ``Q + fixed + {b}`` connected, ``|Q| <= budget``.

    Grows connected sets from ``fixed + {b}`` one neighbour at a time (each set once).
    """
    start = frozenset({base, *fixed})
    comp = nx.node_connected_component(g, base)
    start = frozenset(v for v in start if v in comp)
    best = 0.0
    frontier = {start}
    seen = {start}
    for _ in range(budget):
        nxt = set()
        for s in frontier:
            for v in {u for w in s for u in g[w]} - s - set(fixed):
                t = s | {v}
                if t not in seen:
                    seen.add(t)
                    nxt.add(t)
                    best = max(best, sum(utilities.get(u, 0.0) for u in t))
        frontier = nxt
    return best


def random_case(seed: int):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(14, 21))
    if seed % 2:
        g = nx.connected_watts_strogatz_graph(n, 4, 0.3, seed=seed)
    else:
        g = nx.gnp_random_graph(n, float(rng.uniform(0.12, 0.3)), seed=seed)
    fixed = []
    if seed % 3 == 0 and len(g[0]):
        fixed = [int(rng.choice(sorted(g[0])))]
    cand = [v for v in range(1, n) if v not in fixed]
    frontiers = rng.choice(cand, size=int(rng.integers(3, 9)), replace=False)
    utilities = {int(f): float(rng.choice([1.0, 2.0, rng.uniform(0.1, 5)])) for f in frontiers}
    return g, utilities, int(rng.integers(1, 7)), fixed


@pytest.mark.parametrize("backend", ["scip", "highs"])
@pytest.mark.parametrize("seed", range(24))
def test_node_model_matches_enumeration(seed: int, backend: str) -> None:
    g, utilities, budget, fixed = random_case(seed)
    opt = connected_best(g, 0, utilities, budget, fixed)
    conf = optimal_configuration(g, 0, utilities, budget, "ilp", fixed=fixed, backend=backend)
    assert conf.proven_optimal
    assert conf.utility == pytest.approx(opt, abs=1e-9)
    problems = check_configuration(g, 0, conf.vertices, utilities, budget, fixed=fixed)
    assert [p for p in problems if not (opt == 0 and p.startswith("(I)"))] == []


@pytest.mark.parametrize("seed", range(3))
def test_node_and_arc_models_agree(seed: int, monkeypatch: pytest.MonkeyPatch) -> None:
    inst = exploration_instance(
        seed, n_vertices=80, n_edges=520, n_frontiers=14, n_robots=7, n_busy=seed % 2
    )
    args = (inst.graph, inst.base, inst.utilities, inst.budget)
    fixed = set(inst.goals.values())
    got = {}
    for form in ("node", "arc"):
        monkeypatch.setattr(ilp, "FORMULATION", form)
        for backend in ("scip", "highs"):
            c = optimal_configuration(*args, "ilp", fixed=fixed, backend=backend)
            assert c.proven_optimal
            got[form, backend] = c.utility
    assert max(got.values()) - min(got.values()) <= 1e-9 * max(got.values())


def _model(seed: int) -> NodeSeparatorModel:
    inst = exploration_instance(seed, n_vertices=70, n_edges=450, n_frontiers=12, n_robots=7)
    prob = _problem.build(inst.graph, inst.base, inst.utilities, inst.budget)
    return NodeSeparatorModel(prob, reduce_dominated(prob))


def test_integral_separation() -> None:
    dm = _model(0)
    y = np.zeros(dm.n_cols)
    far = [v for v in range(1, dm.n) if not dm.root_linked[v]]
    y[dm.ycol(far[0])] = 1.0  # alone, away from b: cut off
    cuts = dm.separate_integral(np.zeros(0), y)
    assert cuts
    for cols, k in cuts:  # violated by y, and a separator: b and k on either side
        assert y[cols].sum() < y[dm.ycol(k)]
        keep = np.ones(dm.n, dtype=bool)
        keep[cols + 1] = False
        sub = dm.adj[keep][:, keep]
        idx = np.flatnonzero(keep)
        comp = nx.node_connected_component(nx.from_scipy_sparse_array(sub), 0)
        assert int(np.flatnonzero(idx == k)[0]) not in comp
    linked = np.flatnonzero(dm.root_linked[1:]) + 1
    y[:] = 0.0
    y[dm.ycol(int(linked[0]))] = 1.0
    assert dm.separate_integral(np.zeros(0), y) == []


@pytest.mark.skipif(not jit.available(), reason="needs numba")
@pytest.mark.parametrize("seed", range(2))
def test_node_separation_same_cuts_with_kernel(seed: int) -> None:
    dm = _model(seed)
    rng = np.random.default_rng(seed)
    for _ in range(5):
        y = np.where(rng.random(dm.n_cols) < 0.4, rng.random(dm.n_cols), 0.0)
        with jit.using(False):
            ref = dm.separate_fractional(np.zeros(0), y)
        with jit.using(True):
            got = dm.separate_fractional(np.zeros(0), y)
        assert len(ref) == len(got)
        for (a, k), (b, j) in zip(ref, got, strict=True):
            assert k == j and np.array_equal(a, b)
            assert y[a].sum() < y[dm.ycol(k)] - 1e-6  # violated


@pytest.mark.parametrize("kernel", [False, True] if jit.available() else [False])
def test_minimal_separator(kernel: bool) -> None:
    dm = _model(1)
    g = nx.from_scipy_sparse_array(dm.adj)
    rng = np.random.default_rng(0)
    checked = 0
    for t in range(1, dm.n):
        if dm.root_linked[t]:
            continue
        # a separator with extra vertices: N(t) plus random others (not 0, not t)
        extra = rng.choice(np.arange(1, dm.n), size=10, replace=False)
        sep = np.union1d(dm.adj[t].indices, extra[extra != t])
        sep = sep[sep != 0]
        with jit.using(kernel):
            got = dm.minimal(sep, t)
        assert set(got) <= set(sep)
        rest = g.subgraph(set(range(dm.n)) - set(got))
        assert t not in nx.node_connected_component(rest, 0)  # still separates
        side_b = nx.node_connected_component(rest, 0)
        side_t = nx.node_connected_component(rest, t)
        for v in got:  # minimal: every vertex next to both sides
            assert set(g[v]) & side_b and set(g[v]) & side_t
        checked += 1
    assert checked > 5
