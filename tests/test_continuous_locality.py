"""Locality of the connectivity force and of the estimator.

Neighbourhood (see :mod:`tether.continuous.connectivity`): ``N_i`` are the
robots within ``Rs`` of robot ``i``. Robot ``i``'s force depends on its own
state, the positions of ``N_i``, nearby obstacle points and the messages
``(nu_j, C_j, T_j)`` of ``N_i``. Hence:

* with the messages of this step held fixed, moving a robot outside ``N_i``
  (before and after the move) does not change robot ``i``'s force;
* with the messages recomputed (Fiedler vector fixed), moving a robot outside
  the 2-hop neighbourhood does not change it;
* one estimator round of robot ``i`` only uses what its ``G_lambda``
  neighbours sent.
"""

from __future__ import annotations

import numpy as np
import pytest

from tether.comm import CommParams
from tether.continuous.connectivity.estimation import FiedlerEstimator
from tether.continuous.connectivity.gradient import connectivity_force, messages
from tether.continuous.connectivity.params import ConnectivityParams
from tether.continuous.connectivity.weights import compute_weights
from tether.world.clearance import ObstacleIndex
from tether.world.grid import OccupancyGrid
from tether.world.world import World

PARAMS = ConnectivityParams()
LAMBDA2 = 0.3  # any value below lambda2_null gives a non-zero force


def world_with_boxes(rng: np.random.Generator) -> World:
    occ = np.zeros((60, 60, 16), dtype=bool)
    for _ in range(6):
        lo = rng.integers(0, 54, size=3)
        occ[lo[0] : lo[0] + 4, lo[1] : lo[1] + 4, : lo[2] % 10 + 2] = True
    return World(dim=3, grid=OccupancyGrid(occ, 0.5, np.zeros(3)))


def chain_team(rng: np.random.Generator, obs: ObstacleIndex, n: int = 14) -> np.ndarray:
    """A long, thin team (random walk with 2.6-5.5 m steps) so that most robots are far apart."""
    while True:
        steps = rng.normal(size=(n, 3)) * np.array([1.0, 1.0, 0.2])
        steps *= rng.uniform(2.6, 5.5, size=(n, 1)) / np.linalg.norm(steps, axis=1, keepdims=True)
        q = np.array([3.0, 3.0, 3.0]) + np.cumsum(steps, axis=0)
        q[:, :2] = np.abs(q[:, :2])
        if obs.tree.query(q)[0].min() > 0.3:
            return q


def neighbours(q: np.ndarray, i: int) -> np.ndarray:
    return np.flatnonzero(
        (np.linalg.norm(q - q[i], axis=1) < PARAMS.rs_m) & (np.arange(len(q)) != i)
    )


def far_move(
    q: np.ndarray, m: int, avoid: np.ndarray, rng: np.random.Generator
) -> np.ndarray | None:
    """``q`` with robot ``m`` moved so that it stays >= Rs from every robot in ``avoid``."""
    for _ in range(200):
        new = q.copy()
        new[m] = q[m] + rng.normal(scale=1.5, size=3)
        if np.linalg.norm(new[avoid] - new[m], axis=1).min() >= PARAMS.rs_m:
            return new
    return None


@pytest.mark.parametrize("seed", range(12))
def test_force_ignores_robots_outside_the_neighbourhood(seed: int) -> None:
    rng = np.random.default_rng(seed)
    obs = ObstacleIndex.from_world(world_with_boxes(rng))
    q = chain_team(rng, obs)
    graph = compute_weights(q, PARAMS, obs)
    nu = rng.normal(size=len(q))  # any received values: locality must not rely on them
    msg = messages(graph, nu)  # what every robot sent this step
    force = connectivity_force(graph, LAMBDA2, msg, PARAMS)
    checked = changed = 0
    for i in range(len(q)):
        others = np.setdiff1d(np.arange(len(q)), np.r_[i, neighbours(q, i)])
        for m in others:
            moved = far_move(q, m, np.array([i]), rng)
            if moved is None:
                continue
            f_new = connectivity_force(compute_weights(moved, PARAMS, obs), LAMBDA2, msg, PARAMS)
            np.testing.assert_allclose(f_new[i], force[i], rtol=1e-12, atol=1e-15)
            checked += 1
            # the robots that do see m generally feel the move: the test can fail
            changed += int(not np.allclose(f_new, force, rtol=1e-12, atol=1e-15))
    assert checked > 20 and changed > 0


def test_force_with_fresh_messages_is_two_hop_local() -> None:
    checked = 0
    for seed in range(8):
        rng = np.random.default_rng(100 + seed)
        obs = ObstacleIndex.from_world(world_with_boxes(rng))
        q = chain_team(rng, obs, n=24)
        graph = compute_weights(q, PARAMS, obs)
        nu = rng.normal(size=len(q))  # the eigenvector estimate is held fixed
        force = connectivity_force(graph, LAMBDA2, messages(graph, nu), PARAMS)
        for i in range(len(q)):
            one = neighbours(q, i)
            two = np.unique(np.concatenate([one] + [neighbours(q, j) for j in one] + [[i]]))
            for m in np.setdiff1d(np.arange(len(q)), two):
                moved = far_move(q, m, two[two != m], rng)
                if moved is None:
                    continue
                g2 = compute_weights(moved, PARAMS, obs)
                f_new = connectivity_force(g2, LAMBDA2, messages(g2, nu), PARAMS)
                np.testing.assert_allclose(f_new[i], force[i], rtol=1e-12, atol=1e-15)
                checked += 1
    assert checked > 20


@pytest.mark.parametrize("seed", range(5))
def test_estimator_round_uses_only_neighbours(seed: int) -> None:
    rng = np.random.default_rng(200 + seed)
    obs = ObstacleIndex.from_world(world_with_boxes(rng))
    q = chain_team(rng, obs)
    graph = compute_weights(q, PARAMS, obs)
    pairs, _ = graph.active()
    n = len(q)
    est_a = FiedlerEstimator.create(n, np.random.default_rng(seed), comm=CommParams())
    est_a.update(graph, 50)
    est_b = FiedlerEstimator.create(n, np.random.default_rng(seed), comm=CommParams())
    est_b.update(graph, 50)
    np.testing.assert_array_equal(est_a.state, est_b.state)
    m = int(rng.integers(n))
    est_b.state[m] += rng.normal(size=5)  # robot m's state differs
    est_a.update(graph, 1)
    est_b.update(graph, 1)
    linked = np.zeros(n, dtype=bool)
    linked[pairs[(pairs == m).any(axis=1)].ravel()] = True
    linked[m] = True
    np.testing.assert_array_equal(est_a.state[~linked], est_b.state[~linked])
    assert not np.array_equal(est_a.state[linked], est_b.state[linked])
