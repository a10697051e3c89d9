"""The non-communicating Local Steering Strategy (Kerestecioglu & Cezayirli)."""

from __future__ import annotations

import numpy as np
import pytest

from tether.paths.trajectory import Polyline
from tether.sensing import SensorModel, sense
from tether.silent.steering import (
    constrained_steps,
    desired_steps,
    satisfies_constraints,
)
from tether.silent.strategy import SilentStrategy
from tether.sim import StepContext, TeamState, simulate
from tether.team import random_connected
from tether.world.world import World

D_MAX = 15.0
DR = 0.03 * D_MAX
DTHETA = np.radians(12)


def _cost13(x: np.ndarray, rel: np.ndarray, d0: float) -> float:
    return float(np.sum((np.linalg.norm(x - rel, axis=1) - d0) ** 2))


@pytest.mark.parametrize("seed", range(10))
def test_eq15_is_the_gradient_step_of_cost13(seed):
    """Eq. (15) equals -gamma * grad J(0) of cost (13), checked by central differences."""
    rng = np.random.default_rng(seed)
    dim = 2 + seed % 2
    rel = rng.uniform(-10, 10, (6, dim))
    gamma, d0 = 0.2, 7.0
    step = desired_steps(rel, np.zeros(6, int), 1, gamma=gamma, d0_m=d0)[0]
    h = 1e-6
    grad = np.array(
        [(_cost13(h * e, rel, d0) - _cost13(-h * e, rel, d0)) / (2 * h) for e in np.eye(dim)]
    )
    np.testing.assert_allclose(step, -gamma * grad, rtol=1e-5, atol=1e-6)


def test_farthest_cost_steps_towards_the_farthest_robot():
    rel = np.array([[3.0, 0.0], [0.0, -9.0], [-5.0, 0.0]])
    step = desired_steps(rel, np.zeros(3, int), 1, cost="farthest", gamma=0.5)[0]
    np.testing.assert_allclose(step, [0.0, -0.5])


@pytest.mark.parametrize("seed", range(200))
def test_constrained_step_keeps_every_pair_condition_for_true_positions(seed):
    """Per-pair form of (1)-(2) holds for the TRUE positions despite bounded noise."""
    rng = np.random.default_rng(seed)
    dim = 2 + seed % 2
    true_rel = rng.normal(size=(rng.integers(1, 8), dim))
    true_rel *= rng.uniform(1.0, D_MAX, len(true_rel))[:, None] / np.linalg.norm(
        true_rel, axis=1, keepdims=True
    )
    sensor = SensorModel(D_MAX, radial_error_m=DR, angular_error_rad=DTHETA, noise="bound")
    positions = np.vstack([np.zeros(dim), true_rel])
    obs = sense(positions, SensorModel(100.0, noise="none"), rng)
    from tether.sensing.robots import _noisy

    measured = _noisy(obs.of(0), sensor, rng)
    desired = rng.normal(size=(1, dim)) * rng.uniform(0.1, 20)
    step = constrained_steps(
        desired,
        measured,
        np.zeros(len(measured), int),
        d_max_m=D_MAX,
        radial_error_m=DR,
        angular_error_rad=DTHETA,
    )[0]
    assert satisfies_constraints(step, obs.of(0), d_max_m=D_MAX)
    # the step keeps the desired direction and never grows
    assert np.linalg.norm(step) <= np.linalg.norm(desired) + 1e-12
    if np.linalg.norm(step) > 0:
        cos = step @ desired[0] / (np.linalg.norm(step) * np.linalg.norm(desired))
        assert cos == pytest.approx(1.0)


def _random_polyline(rng: np.random.Generator, start: np.ndarray, dim: int) -> Polyline:
    """A path with sharp (up to 150 degree) turns, as in the paper's section V."""
    pts = [start]
    heading = rng.normal(size=dim)
    for _ in range(4):
        heading = heading / np.linalg.norm(heading)
        pts.append(pts[-1] + heading * rng.uniform(10, 30))
        heading = heading + rng.normal(size=dim) * 1.5
    return Polyline(np.asarray(pts))


@pytest.mark.parametrize("block", range(10))
def test_true_graph_never_disconnects_over_300_seeds(block):
    """Theorem 1 with noise at its bounds and occlusion: 300 random starts, 10 blocks of 30."""
    for seed in range(block * 30, block * 30 + 30):
        rng = np.random.default_rng(seed)
        dim = 2 if seed % 3 else 3
        n = int(rng.integers(4, 22))
        world = World(dim=dim)
        spacing = rng.uniform(5.0, 14.0)
        pos = random_connected(n, world, rng, spacing, 1.2, np.zeros(dim))
        sensor = SensorModel(
            D_MAX,
            body_radius_m=0.5,
            occlusion=True,
            radial_error_m=DR,
            angular_error_rad=DTHETA,
            noise="bound",
        )
        strategy = SilentStrategy(
            d_max_m=D_MAX,
            trajectory=_random_polyline(rng, pos[0], dim),
            cost=str(rng.choice(["desired_distance", "farthest"])),
            d0_m=float(rng.uniform(3.0, 13.0)),
            gamma=float(rng.uniform(0.05, 0.5)),
            radial_error_m=DR,
            angular_error_rad=DTHETA,
            speed_mps=float(rng.uniform(0.5, 3.0)),
            min_separation_m=float(rng.choice([0.0, 1.0])),
        )
        result = simulate(
            world, sensor, strategy, TeamState.at_rest(pos), dt_s=1.0, max_steps=40, rng=rng
        )
        assert result.records[0].connected
        broken = [r.step for r in result.records if not r.connected]
        assert not broken, f"seed {seed}: disconnected at steps {broken[:5]}"


@pytest.mark.parametrize(
    ("seed", "dim", "cost", "d0"),
    [
        (0, 2, "desired_distance", 8.0),
        (1, 2, "farthest", 8.0),
        (2, 3, "desired_distance", 6.0),
        (3, 2, "desired_distance", 11.0),
    ],
)
def test_group_follows_the_leader_to_the_end_without_deadlock(seed, dim, cost, d0):
    rng = np.random.default_rng(seed)
    world = World(dim=dim)
    pos = random_connected(12, world, rng, 7.0, 2.0, np.zeros(dim))
    turns = np.array([[0, 0, 0], [40, 0, 0], [40, 30, 0], [0, 30, 10], [0, 60, 10]], float)
    path = Polyline(turns[:, :dim])
    sensor = SensorModel(D_MAX, body_radius_m=0.4, radial_error_m=DR, angular_error_rad=DTHETA)
    strategy = SilentStrategy(
        d_max_m=D_MAX,
        trajectory=path,
        cost=cost,
        d0_m=d0,
        radial_error_m=DR,
        angular_error_rad=DTHETA,
        min_separation_m=1.0,
    )
    result = simulate(
        world, sensor, strategy, TeamState.at_rest(pos), dt_s=1.0, max_steps=3000, rng=rng
    )
    assert strategy.done(), f"leader stuck at progress {strategy.metrics()['path_progress']:.2f}"
    assert result.connected_all_steps
    # the whole (connected) group arrived: every robot within the team's diameter of the goal
    spread = np.linalg.norm(result.final_state.positions - path.end, axis=1).max()
    assert spread < 12 * D_MAX
    assert np.linalg.norm(result.final_state.positions.mean(axis=0) - path.end) < 3 * D_MAX


def test_robot_step_depends_only_on_what_it_senses():
    """Moving a robot that robot i cannot sense leaves i's step unchanged."""
    rng = np.random.default_rng(7)
    world = World(dim=2)
    pos = random_connected(15, world, rng, 8.0, 2.0, np.zeros(2))
    sensor = SensorModel(D_MAX, body_radius_m=0.4, noise="none")
    path = Polyline(np.array([[0.0, 0.0], [50.0, 0.0]]))

    def steps_of(positions: np.ndarray) -> np.ndarray:
        strategy = SilentStrategy(d_max_m=D_MAX, trajectory=path, d0_m=8.0, leader=0)
        state = TeamState.at_rest(positions)
        strategy.reset(world, state, rng)
        obs = sense(positions, sensor, rng, world)
        ctx = StepContext(0, 0.0, 1.0, world, state, obs, rng)
        return strategy.step(ctx).positions - positions

    base = steps_of(pos)
    obs = sense(pos, sensor, rng, world)
    checked = 0
    for i in range(1, 15):
        sensed = set(obs.target[obs.indptr[i] : obs.indptr[i + 1]].tolist()) | {i}
        for k in set(range(1, 15)) - sensed:
            moved = pos.copy()
            moved[k] += rng.normal(size=2) * 3.0
            after = sense(moved, sensor, rng, world)
            if set(after.target[after.indptr[i] : after.indptr[i + 1]].tolist()) != sensed - {i}:
                continue  # k came into view: not a robot i cannot sense
            np.testing.assert_allclose(steps_of(moved)[i], base[i], atol=1e-12)
            checked += 1
    assert checked > 10


@pytest.mark.parametrize("seed", range(100))
def test_direction_search_is_feasible_and_never_worse(seed):
    """The candidate search keeps (1)-(2) for true positions and beats shrink-only progress."""
    rng = np.random.default_rng(1000 + seed)
    dim = 2 + seed % 2
    n = 8
    pos = rng.uniform(-12, 12, (n, dim))
    sensor = SensorModel(D_MAX, radial_error_m=DR, angular_error_rad=DTHETA, noise="bound")
    obs = sense(pos, sensor, rng)
    observer = obs.observer()
    desired = rng.normal(size=(n, dim)) * 3.0
    kwargs = dict(d_max_m=D_MAX, radial_error_m=DR, angular_error_rad=DTHETA)
    plain = constrained_steps(desired, obs.measured, observer, **kwargs)
    search = constrained_steps(desired, obs.measured, observer, search_directions=True, **kwargs)
    for i in range(n):
        rows = slice(obs.indptr[i], obs.indptr[i + 1])
        assert satisfies_constraints(search[i], obs.true_relative[rows], d_max_m=D_MAX)
        assert search[i] @ desired[i] >= plain[i] @ desired[i] - 1e-9
        assert np.linalg.norm(search[i]) <= np.linalg.norm(desired[i]) + 1e-9
