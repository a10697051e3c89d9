"""Optimal configurations: ILP against brute force, APX against its Theorem 4.1 bound.

The oracle enumerates every vertex set ``Q`` on the *original* graph with
``|Q| <= budget``, ``Q`` disjoint from ``fixed + {b}`` and ``Q + fixed + {b}``
connected (constraints II and III of the paper), so it checks the Sec. IV-A
graph transformation as well.
"""

from __future__ import annotations

import itertools

import networkx as nx
import numpy as np
import pytest

from tether.recurrent.planning import problem as _problem
from tether.recurrent.planning.apx import SharedSteiner
from tether.recurrent.planning.configuration import check_configuration, optimal_configuration
from tether.recurrent.planning.steiner import steiner_tree
from tether.recurrent.planning.synthetic import exploration_instance


def brute_force(g: nx.Graph, base, utilities: dict, budget: int, fixed=()) -> tuple[float, int]:
    """Optimal utility and the fewest frontiers an optimal configuration needs."""
    fixed = set(fixed)
    others = [v for v in g if v != base and v not in fixed]
    best, fewest = 0.0, 0
    for r in range(min(budget, len(others)) + 1):
        for q in itertools.combinations(others, r):
            if not nx.is_connected(g.subgraph({base, *fixed, *q})):
                continue
            u = sum(utilities.get(v, 0.0) for v in q)
            nf = sum(1 for v in q if utilities.get(v, 0.0) > 0)
            if u > best + 1e-9 or (abs(u - best) <= 1e-9 and nf < fewest):
                best, fewest = u, nf
    return best, fewest


def random_instance(seed: int, with_fixed: bool):
    rng = np.random.default_rng(seed)
    n = int(rng.integers(6, 12))
    g = nx.gnp_random_graph(n, float(rng.uniform(0.15, 0.45)), seed=seed)
    fixed: list[int] = []
    if with_fixed:  # a previous plan still running: a chain hanging from the base
        cur = 0
        for _ in range(int(rng.integers(1, 3))):
            options = sorted(set(g.neighbors(cur)) - {0, *fixed})
            if not options:
                break
            cur = int(rng.choice(options))
            fixed.append(cur)
    cand = [v for v in range(1, n) if v not in fixed]
    k = int(rng.integers(1, len(cand) + 1))
    frontiers = rng.choice(cand, size=k, replace=False)
    utilities = {
        int(f): float(rng.choice([rng.integers(1, 10), rng.uniform(0.1, 5)])) for f in frontiers
    }
    budget = int(rng.integers(0, 7))
    return g, utilities, budget, fixed


def assert_plan_valid(g, utilities, budget, fixed, conf, opt):
    problems = check_configuration(g, 0, conf.vertices, utilities, budget, fixed=fixed)
    if opt == 0:  # no frontier reachable: (I) cannot hold, the mission ends
        problems = [p for p in problems if not p.startswith("(I)")]
    assert problems == []
    assert conf.robots_used == len(conf.vertices) <= budget
    assert conf.utility == pytest.approx(sum(utilities.get(v, 0.0) for v in conf.vertices))


@pytest.mark.parametrize("backend", ["scip", "highs"])
@pytest.mark.parametrize("seed", range(40))
def test_ilp_matches_brute_force(seed: int, backend: str) -> None:
    g, utilities, budget, fixed = random_instance(seed, with_fixed=seed % 2 == 1)
    opt, _ = brute_force(g, 0, utilities, budget, fixed)
    conf = optimal_configuration(g, 0, utilities, budget, "ilp", fixed=fixed, backend=backend)
    assert conf.proven_optimal
    assert conf.utility == pytest.approx(opt, abs=1e-7)
    assert conf.upper_bound >= opt - 1e-7
    assert_plan_valid(g, utilities, budget, fixed, conf, opt)


@pytest.mark.parametrize("seed", range(120))
def test_apx_within_theorem_bound(seed: int) -> None:
    g, utilities, budget, fixed = random_instance(1000 + seed, with_fixed=seed % 3 == 0)
    delta = 1 + seed % 4
    opt, fewest = brute_force(g, 0, utilities, budget, fixed)
    conf = optimal_configuration(g, 0, utilities, budget, "apx", delta, fixed=fixed)
    k = min(budget, len(utilities))
    assert conf.utility <= opt + 1e-9
    assert conf.utility >= opt * min(1.0, delta / max(k, 1)) - 1e-9  # Theorem 4.1
    if fewest <= delta:  # the optimum uses at most delta frontiers: APX is exact
        assert conf.utility == pytest.approx(opt, abs=1e-9)
    if conf.proven_optimal:
        assert conf.utility == pytest.approx(opt, abs=1e-9)
    assert conf.upper_bound >= opt - 1e-9
    assert_plan_valid(g, utilities, budget, fixed, conf, opt)


@pytest.mark.parametrize("seed", range(12))
def test_shared_dp_equals_steiner_per_subset(seed: int) -> None:
    rng = np.random.default_rng(seed)
    g = nx.connected_watts_strogatz_graph(int(rng.integers(12, 25)), 4, 0.4, seed=seed)
    budget = int(rng.integers(3, 9))
    frontiers = [int(v) for v in rng.choice(np.arange(1, len(g)), size=7, replace=False)]
    utilities = {f: 1.0 for f in frontiers}
    prob = _problem.build(g, 0, utilities, budget)
    fr = prob.frontiers[prob.dist[0, prob.frontiers] <= budget]
    delta = int(rng.integers(1, 6))
    dp = SharedSteiner(prob.dist, fr, budget, delta)
    sub = nx.Graph()
    sub.add_edges_from(
        (prob.labels[a], prob.labels[b]) for a, b in zip(*prob.adj.nonzero(), strict=True)
    )
    sub.add_node(0)
    for s, combos in dp.levels.combos.items():
        if s == dp.delta:
            dp.top_costs(np.arange(len(combos)))
        for r, c in enumerate(combos):
            terms = [prob.labels[int(v)] for v in fr[c]] + [0]
            try:
                exact = steiner_tree(sub, terms).cost
            except nx.NetworkXNoPath:
                exact = np.inf
            # pruned subsets are reported infeasible; they must be so
            want = exact if exact <= budget else budget + 1
            assert dp.costs[s][r] == want or (not dp.alive[s][r] and exact > budget)


@pytest.mark.parametrize("seed", range(2))
def test_exploration_graph_apx_vs_both_ilp_backends(seed: int) -> None:
    inst = exploration_instance(
        seed, n_vertices=70, n_edges=450, n_frontiers=12, n_robots=7, n_busy=2
    )
    args = (inst.graph, inst.base, inst.utilities, inst.budget)
    fixed = set(inst.goals.values())
    scip = optimal_configuration(*args, "ilp", fixed=fixed, backend="scip")
    highs = optimal_configuration(*args, "ilp", fixed=fixed, backend="highs")
    apx = optimal_configuration(*args, "apx", 4, fixed=fixed)
    assert scip.proven_optimal and highs.proven_optimal
    assert scip.utility == pytest.approx(highs.utility, rel=1e-9)
    k = min(inst.budget, len(inst.utilities))
    assert scip.utility * min(1.0, 4 / k) - 1e-9 <= apx.utility <= scip.utility + 1e-9
    for conf in (scip, highs, apx):
        assert (
            check_configuration(
                inst.graph, inst.base, conf.vertices, inst.utilities, inst.budget, fixed=fixed
            )
            == []
        )


def test_checker_reports_violations() -> None:
    g = nx.path_graph(6)  # 0 - 1 - 2 - 3 - 4 - 5
    frontiers = {5}
    assert check_configuration(g, 0, {1, 2, 3, 4, 5}, frontiers, 5) == []
    assert any(p.startswith("(II)") for p in check_configuration(g, 0, {1, 2, 5}, frontiers, 5))
    assert any(p.startswith("(I)") for p in check_configuration(g, 0, {1, 2}, frontiers, 5))
    assert any(
        p.startswith("budget") for p in check_configuration(g, 0, {1, 2, 3, 4, 5}, frontiers, 4)
    )
    assert any(
        p.startswith("budget")
        for p in check_configuration(g, 0, {2, 3}, frontiers, 4, fixed={1, 2})
    )
    # (III): a non-ready robot's goal dropped; (IV): a disconnected one moved
    probs = check_configuration(
        g,
        0,
        {3, 4, 5},
        frontiers,
        3,
        fixed={1},
        assignment={"a": 3, "b": 4, "e": 5},
        previous_goals={"d": 2, "e": 1},
        ready={"a", "b", "c"},
        connected=(),
    )
    assert any(p.startswith("(III)") for p in probs)
    assert any(p.startswith("(IV)") for p in probs)
    assert any(p.startswith("(II)") for p in probs)  # vertex 2 left empty


def test_invalid_inputs() -> None:
    g = nx.path_graph(4)
    with pytest.raises(ValueError):
        optimal_configuration(g, 9, {3: 1.0}, 2)
    with pytest.raises(ValueError):
        optimal_configuration(g, 0, {3: -1.0}, 2)
    with pytest.raises(ValueError):
        optimal_configuration(g, 0, {3: 1.0}, -1)
    with pytest.raises(ValueError):
        optimal_configuration(g, 0, {3: 1.0}, 2, method="greedy")
    with pytest.raises(ValueError):
        optimal_configuration(g, 0, {3: 1.0}, 2, delta=0)
    with pytest.raises(ValueError):
        optimal_configuration(nx.DiGraph(g), 0, {3: 1.0}, 2)
    out = optimal_configuration(g, 0, {3: 1.0}, 2)  # frontier out of reach
    assert out.vertices == frozenset() and out.utility == 0.0
