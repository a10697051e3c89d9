"""The lazy shared Steiner DP of APX against an exact Steiner tree per subset.

``LazySteiner`` computes DP rows only when Algorithm 1 asks for a subset and prunes
by Step 6 and the closed list; whatever order subsets are asked in, every answer
must equal ``min(steiner cost of F + {b}, budget + 1)``: pruning may only remove
infeasible subsets.
"""

from __future__ import annotations

import itertools

import networkx as nx
import numpy as np
import pytest

from tether import jit
from tether.recurrent.planning import problem as _problem
from tether.recurrent.planning.apx import LazySteiner
from tether.recurrent.planning.steiner import steiner_tree


def _instance(
    rng: np.random.Generator, seed: int, sizes: tuple[int, int], n_frontiers: int, budgets: tuple
) -> tuple[_problem.Problem, np.ndarray, int, nx.Graph]:
    """A small-world graph's reduced problem, its frontiers within the budget, the
    budget, and the reduced graph (labels) for exact Steiner trees."""
    g = nx.connected_watts_strogatz_graph(int(rng.integers(*sizes)), 4, 0.3, seed=seed)
    frontiers = [int(v) for v in rng.choice(np.arange(1, len(g)), size=n_frontiers, replace=False)]
    budget = int(rng.integers(*budgets))
    prob = _problem.build(g, 0, dict.fromkeys(frontiers, 1.0), budget)
    fr = prob.frontiers[prob.dist[0, prob.frontiers] <= budget]
    sub = nx.Graph()
    sub.add_edges_from(
        (prob.labels[a], prob.labels[b]) for a, b in zip(*prob.adj.nonzero(), strict=True)
    )
    sub.add_node(0)
    return prob, fr, budget, sub


@pytest.mark.parametrize("unit_graph", [False, True])
@pytest.mark.parametrize("seed", range(10))
def test_lazy_costs_equal_exact_steiner_in_any_order(seed: int, unit_graph: bool) -> None:
    rng = np.random.default_rng(100 + seed)
    prob, fr, budget, sub = _instance(rng, seed, (12, 22), 7, (3, 8))
    delta = int(rng.integers(2, 5))
    lazy = LazySteiner(prob.dist, fr, budget, delta, unit_graph=unit_graph)
    assert (lazy.graph is not None) == unit_graph  # budget >= 3: the graph search is used
    asks = [
        np.array(c)
        for s in range(1, min(delta, len(fr)) + 1)
        for c in itertools.combinations(range(len(fr)), s)
    ]
    if unit_graph:
        pytest.importorskip("numba")
    for k in rng.permutation(len(asks)):  # a random order: the memo and row stores must agree
        combo = asks[k]
        with jit.using(unit_graph):  # the graph search is the compiled path
            got = int(lazy.steiner_costs(combo[None, :])[0])
        terms = [prob.labels[int(v)] for v in fr[combo]] + [0]
        try:
            exact = steiner_tree(sub, terms).cost
        except nx.NetworkXNoPath:
            exact = np.inf
        assert got == min(exact, budget + 1), (combo, got, exact)


@pytest.mark.parametrize("seed", range(8))
def test_apx_with_more_frontiers_per_subset_than_robots_is_exact(seed: int) -> None:
    """delta > budget: subsets stop at `budget` frontiers and APX is still exact (k <= delta)."""
    from itertools import combinations

    from tether.recurrent.planning.configuration import optimal_configuration

    rng = np.random.default_rng(500 + seed)
    g = nx.random_geometric_graph(40, 0.35, seed=seed)
    g = g.subgraph(max(nx.connected_components(g), key=len)).copy()
    nodes = sorted(g)
    base, budget = nodes[0], int(rng.integers(1, 4))
    frontiers = rng.choice(nodes[1:], size=min(15, len(nodes) - 1), replace=False)
    utilities = {int(f): float(rng.uniform(0.5, 5.0)) for f in frontiers}
    conf = optimal_configuration(g, base, utilities, budget, method="apx", delta=4)
    best = 0.0  # brute force over every connected set of <= budget robots
    others = [v for v in nodes if v != base]
    for r in range(1, budget + 1):
        for q in combinations(others, r):
            if nx.is_connected(g.subgraph([base, *q])):
                best = max(best, sum(utilities.get(v, 0.0) for v in q))
    assert conf.utility == pytest.approx(best, abs=1e-9)
    assert conf.proven_optimal


@pytest.mark.parametrize("seed", range(10))
def test_relax_kernel_matches_numpy(seed: int) -> None:
    """The compiled min-plus relaxation gives the numpy reference's integers."""
    pytest.importorskip("numba")
    from tether import jit
    from tether.recurrent.planning.apx import _relax

    rng = np.random.default_rng(seed)
    n, cap = int(rng.integers(2, 60)), int(rng.integers(2, 12))
    for dtype in (np.int16, np.int32):
        d = rng.integers(0, cap + 1, size=(n, n)).astype(dtype)
        g = rng.integers(0, 2 * cap + 1, size=(int(rng.integers(1, 40)), n)).astype(dtype)
        with jit.using(False):
            want = _relax(g, d, cap)
        with jit.using(True):
            got = _relax(g, d, cap)
        assert got.dtype == want.dtype and np.array_equal(got, want)
        brute = np.minimum((g[:, :, None].astype(int) + d[None]).min(axis=1), cap)
        assert np.array_equal(want, brute)


@pytest.mark.parametrize("seed", range(12))
def test_relax_graph_kernel_matches_numpy(seed: int) -> None:
    """Breadth-first relaxation on the graph = the min-plus reference on its hop counts.

    Random graphs (some disconnected, so clipped unreachable distances occur), labels
    above the clip, both dtypes; catches a level loop one short, labels not clipped
    before the search, or a search that lets a label rise.
    """
    pytest.importorskip("numba")
    from tether.recurrent.planning.apx import _relax

    rng = np.random.default_rng(300 + seed)
    n = int(rng.integers(2, 70))
    g_nx = nx.gnp_random_graph(n, float(rng.choice([0.03, 0.08, 0.3])), seed=seed)
    hops = dict(nx.all_pairs_shortest_path_length(g_nx))
    cap = int(rng.integers(2, 12))
    for dtype in (np.int16, np.int32):
        d = np.full((n, n), cap, dtype=dtype)
        for u, row in hops.items():
            for v, h in row.items():
                d[u, v] = min(h, cap)
        lazy = LazySteiner(d, np.arange(min(2, n)), cap - 1, 2, unit_graph=True)
        g = rng.integers(0, 2 * cap + 1, size=(int(rng.integers(1, 30)), n)).astype(dtype)
        with jit.using(False):
            want = _relax(g, d, cap)
        with jit.using(True):
            got = _relax(g, d, cap, lazy.graph)
        assert got.dtype == want.dtype and np.array_equal(got, want)


@pytest.mark.parametrize("seed", range(10))
def test_pair_filter_is_exactly_pair_feasibility(seed: int) -> None:
    """``pair_ok[i, j]``: the Steiner tree of ``{b, f_i, f_j}`` fits the budget.

    Against networkx's exact tree per pair; catches the E rows read at frontier
    positions instead of their vertices, or a filter stricter than feasibility (it
    would drop feasible subsets).
    """
    rng = np.random.default_rng(700 + seed)
    prob, fr, budget, sub = _instance(rng, seed, (14, 26), 8, (3, 7))
    lazy = LazySteiner(prob.dist, fr, budget, 4, unit_graph=bool(seed % 2))
    assert lazy.pair_ok is not None and lazy.pair_ok.shape == (len(fr), len(fr))
    for i, j in itertools.combinations(range(len(fr)), 2):
        terms = [prob.labels[int(fr[i])], prob.labels[int(fr[j])], 0]
        try:
            fits = steiner_tree(sub, terms).cost <= budget
        except nx.NetworkXNoPath:
            fits = False
        assert lazy.pair_ok[i, j] == lazy.pair_ok[j, i] == fits, (i, j)
    assert LazySteiner(prob.dist, fr, budget, 4, pair_filter=False).pair_ok is None


@pytest.mark.parametrize("seed", range(6))
def test_apx_with_and_without_the_pair_filter_agree(seed: int) -> None:
    """Algorithm 1's result does not depend on the pair filter (the reference: off).

    Exploration-shaped instances (many frontiers, budgets 3-8, some robots busy);
    every field but the work counter, and the configuration ``optimal_configuration``
    returns. Catches a filter that drops a feasible subset or reorders the others.
    """
    from tether.recurrent.planning.apx import solve_apx
    from tether.recurrent.planning.synthetic import exploration_instance

    inst = exploration_instance(seed, n_frontiers=40, n_busy=seed % 3)
    for budget in (3, 4, 6, 8):
        args = (inst.graph, inst.base, inst.utilities, budget, list(inst.goals.values()))
        prob = _problem.build(*args)
        for delta in (3, 4):
            with jit.using(bool(seed % 2)):
                on, off = solve_apx(prob, delta), solve_apx(prob, delta, pair_filter=False)
            assert (on.vertices, on.utility, on.best_subset_utility) == (
                off.vertices,
                off.utility,
                off.best_subset_utility,
            )
            assert (on.proven_optimal, on.upper_bound, on.subsets_total) == (
                off.proven_optimal,
                off.upper_bound,
                off.subsets_total,
            )
