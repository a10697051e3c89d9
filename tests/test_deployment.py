"""Deployments (Sec. V): Hungarian optimality against brute force, constraints (I)-(IV)."""

from __future__ import annotations

import itertools

import networkx as nx
import numpy as np
import pytest

from tether.recurrent.planning.configuration import check_configuration, optimal_configuration
from tether.recurrent.planning.deployment import optimal_deployment
from tether.recurrent.planning.synthetic import exploration_instance


def brute_force_assignment(robots, targets, cost) -> float:
    best = np.inf
    for chosen in itertools.permutations(robots, len(targets)):
        best = min(best, sum(cost(r, t) for r, t in zip(chosen, targets, strict=True)))
    return best


@pytest.mark.parametrize("seed", range(40))
def test_hungarian_minimizes_total_travel(seed: int) -> None:
    rng = np.random.default_rng(seed)
    g = nx.connected_watts_strogatz_graph(14, 4, 0.3, seed=seed)
    pos = rng.uniform(0, 10, size=(14, 2))
    n_ready = int(rng.integers(1, 6))
    where = {f"r{i}": int(rng.integers(14)) for i in range(n_ready + 2)}
    ready = [f"r{i}" for i in range(n_ready)]
    busy = {f"r{n_ready}": 13, f"r{n_ready + 1}": 12}
    q = [
        int(v)
        for v in rng.choice(np.arange(1, 12), size=int(rng.integers(0, n_ready + 1)), replace=False)
    ]

    def cost(r, v):
        return float(np.linalg.norm(pos[where[r]] - pos[v]))

    dep = optimal_deployment(g, 0, q, ready, cost, connected_busy=busy, fixed=busy.values())
    targets = [*q, *busy.values()]
    real = {r: v for r, v in dep.assignment.items() if v in targets}
    assert sorted(real.values()) == sorted(targets)  # every goal gets exactly one robot
    stage1 = sum(cost(r, v) for r, v in real.items())
    assert stage1 == pytest.approx(brute_force_assignment([*ready, *busy], targets, cost))
    # surplus robots wait next to the configuration (or at the base)
    occupied = set(targets) | {0}
    for v in dep.assignment.values():
        if v not in targets:
            assert v == 0 or any(u in occupied for u in g.neighbors(v))
            assert v in dep.fake_frontiers or v == 0
    assert set(dep.assignment) == {*ready, *busy}
    assert dep.total_cost == pytest.approx(sum(cost(r, v) for r, v in dep.assignment.items()))


def test_surplus_beyond_fake_frontiers_wait_at_base() -> None:
    g = nx.path_graph(3)  # 0 - 1 - 2
    dep = optimal_deployment(g, 0, [1], ["a", "b", "c", "d"], lambda r, v: 1.0)
    goals = sorted(dep.assignment.values())
    assert goals == [0, 0, 1, 2]
    assert dep.fake_frontiers == frozenset({2})


def test_too_many_goals_rejected() -> None:
    with pytest.raises(ValueError):
        optimal_deployment(nx.path_graph(4), 0, [1, 2, 3], ["a"], lambda r, v: 0.0)


@pytest.mark.parametrize("method", ["apx", "ilp"])
@pytest.mark.parametrize("seed", range(3))
def test_full_plan_satisfies_constraints(seed: int, method: str) -> None:
    inst = exploration_instance(
        seed, n_vertices=60, n_edges=400, n_frontiers=10, n_robots=7, n_busy=3
    )
    fixed = set(inst.goals.values())
    conf = optimal_configuration(
        inst.graph, inst.base, inst.utilities, inst.budget, method, fixed=fixed
    )
    busy = sorted(inst.goals)
    connected = busy[:2]  # say the first two busy robots can talk to the BS right now

    def cost(r, v):
        return float(inst.travel_m[inst.robots[r], v])

    dep = optimal_deployment(
        inst.graph,
        inst.base,
        conf.vertices,
        inst.ready,
        cost,
        connected_busy={r: inst.goals[r] for r in connected},
        fixed=fixed,
    )
    full = dict(dep.assignment)
    for r in busy:
        full.setdefault(r, inst.goals[r])  # non-connected robots keep their goals
    problems = check_configuration(
        inst.graph,
        inst.base,
        conf.vertices,
        inst.utilities,
        inst.budget,
        fixed=fixed,
        assignment=full,
        previous_goals=inst.goals,
        ready=inst.ready,
        connected=connected,
    )
    assert problems == []
