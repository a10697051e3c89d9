"""Exploration simulator: knowledge flow, motion, readiness paths, Utility baseline."""

from __future__ import annotations

import itertools

import networkx as nx
import numpy as np
import pytest

from _exploration_helpers import Idle, farthest_known_path, office
from tether.recurrent.baseline_utility import UtilityStrategy
from tether.recurrent.exploration.knowledge import Knowledge
from tether.recurrent.exploration.sim import ExplorationConfig, ExplorationSim, GoalKind
from tether.recurrent.planning.readiness import ReadinessTracker, relay_paths


# ---------------------------------------------------------------- knowledge
def test_knowledge_flush_only_through_bs_group() -> None:
    rng = np.random.default_rng(0)
    k = Knowledge((20, 20), 3)
    cells = [rng.choice(400, 30, replace=False) for _ in range(3)]
    for r in range(3):
        k.observe(r, cells[r])
    k.exchange([[0], [1, 2]], [True, False])
    assert set(np.flatnonzero(k.global_known)) == set(cells[0].tolist())
    assert np.array_equal(k.local_known[1], k.local_known[2])  # shared in the group
    # robot 1 reconnects: everything it gathered (and got from 2) is flushed
    k.exchange([[0, 1], [2]], [True, False])
    want = set(np.concatenate(cells).tolist())
    assert set(np.flatnonzero(k.global_known)) == want
    assert np.array_equal(k.local_known[0], k.global_known)


# ---------------------------------------------------------------- readiness
@pytest.mark.parametrize("seed", range(15))
def test_relay_paths_first_forming_shortest(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(3, 8))
    g = nx.gnp_random_graph(n + 1, 0.45, seed=seed)  # vertex 0 = BS, robot r -> vertex r + 1
    edges = np.array(list(g.edges)).reshape(-1, 2)
    goals = {r: r + 1 for r in range(n)}
    times = {r: float(rng.integers(0, 5)) for r in range(n)}
    targets = list(range(n))
    paths = relay_paths(goals, times, targets, edges, base=0)
    for f in targets:
        # oracle: earliest time T at which f joins the BS using goals of robots arriving by T
        cands = sorted({t for t in times.values() if t >= times[f]})
        first = None
        for T in cands:
            sub = g.subgraph([0] + [goals[r] for r in range(n) if times[r] <= T])
            if nx.has_path(sub, goals[f], 0):
                first = (T, nx.shortest_path_length(sub, goals[f], 0))
                break
        if first is None:
            assert paths[f] is None
            continue
        members = paths[f]
        assert members[0] == f
        assert max(times[m] for m in members) <= first[0]
        assert len(members) == first[1]  # shortest in that restricted graph
        walk = [goals[m] for m in members] + [0]
        assert all(g.has_edge(a, b) for a, b in itertools.pairwise(walk))


def test_tracker_binds_until_delivered() -> None:
    tr = ReadinessTracker()
    keys = np.array([10, 11, 12])  # robot r heads to location keys[r]
    tr.add(10, [10, 11])  # robot 0's frontier relayed by robot 1
    done = np.ones(3, bool)
    conn = np.ones(3, bool)
    at_goal = np.ones(3, bool)
    assert tr.ready(done, conn, keys).tolist() == [False, False, True]
    tr.update(keys, at_goal, np.array([False, True, True]))
    assert tr.ready(done, conn, keys).tolist() == [False, False, True]
    tr.update(keys, at_goal, np.array([True, True, True]))
    assert tr.ready(done, conn, keys).tolist() == [True, True, True]
    assert tr.ready(done, np.array([True, False, True]), keys).tolist() == [True, False, True]
    tr.add(12, [12, 11])
    assert tr.branch(2, keys) == {1, 2}


# ---------------------------------------------------------------- simulator
def test_initial_state_and_motion_speed() -> None:
    occ = office(1)
    cfg = ExplorationConfig(n_robots=4, steps=10)
    sim = ExplorationSim(occ, np.array([60.0, 80.0]), Idle(), cfg)
    assert sim.connected.all()
    assert sim.knowledge.global_known.any()
    # send robot 0 along a long known path and check speed and free space
    path = farthest_known_path(sim, 0)
    sim.assign(0, path[-1], GoalKind.FRONTIER, path)
    prev = sim.pos[0].copy()
    for _ in range(200):
        sim.step()
        assert np.linalg.norm(sim.pos[0] - prev) <= cfg.speed_cells + 1e-9
        c = np.floor(sim.pos[0]).astype(int)
        assert not occ[c[0], c[1]]
        prev = sim.pos[0].copy()
        if sim.at_goal[0] and sim.scanned[0]:
            break
    assert sim.at_goal[0] and sim.scanned[0]
    assert np.allclose(sim.pos[0], path[-1])


@pytest.mark.parametrize("delay", [0, 1, 3])
def test_assignment_delay_holds_robot_that_many_steps(delay: int) -> None:
    """Fig. 4a: a plan that took ``delay`` steps costs the robot exactly ``delay`` steps."""
    occ = office(1)
    sim = ExplorationSim(occ, np.array([60.0, 80.0]), Idle(), ExplorationConfig(n_robots=2))
    path = farthest_known_path(sim, 0)
    sim.assign(0, path[-1], GoalKind.RELAY, path, delay=delay)
    start = sim.pos[0].copy()
    for _ in range(delay):
        sim.step()
        assert np.allclose(sim.pos[0], start)
    sim.step()
    assert not np.allclose(sim.pos[0], start)


@pytest.mark.parametrize("seed", range(3))
def test_utility_baseline_invariants(seed: int) -> None:
    occ = office(seed)
    cfg = ExplorationConfig(n_robots=4, steps=80)
    rng = np.random.default_rng(seed)
    from tether.recurrent.exploration.sim import random_base

    sim = ExplorationSim(occ, random_base(occ, 3, rng), UtilityStrategy(), cfg)
    sim.strategy.start(sim)
    prev_global = sim.knowledge.global_known.copy()
    explored = [sim.explored_fraction()]
    for _ in range(cfg.steps):
        sim.step()
        explored.append(sim.explored_fraction())
        g = sim.knowledge.global_known
        assert (g >= prev_global).all()  # the BS never forgets
        if (g != prev_global).any():
            assert sim.connected.any()  # it only learns from connected robots
        union = np.logical_or.reduce(sim.knowledge.local_known, axis=0)
        assert not (g & ~union).any()  # it knows nothing no robot sensed
        prev_global = g.copy()
        cells = np.floor(sim.pos).astype(int)
        assert not occ[cells[:, 0], cells[:, 1]].any()
    assert np.all(np.diff(explored) >= 0)
    assert explored[-1] > explored[0]
    assert 0 < explored[-1] <= 1
