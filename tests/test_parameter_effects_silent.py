"""Every parameter of strategy ``silent`` changes a run the way its documentation says."""

from __future__ import annotations

import sys
import types

import numpy as np
import pytest

from _parameter_runs import SILENT, changed, leader_circle, ran
from _parameters import effect

#: ten robots scattered, noisy sensing (the paper's kind of setting), 40 steps
TEAM = changed(
    SILENT,
    team__n_robots=10,
    team__init={"kind": "random_connected", "spacing_m": 6.0, "min_separation_m": 2.0},
    sensing={"range_m": 15.0, "body_radius_m": 0.4, "radial_error_m": 0.45,
             "angular_error_deg": 12.0, "noise": "bound"},
    sim__max_steps=40,
)  # fmt: skip
START = {"kind": "positions", "positions": [[0, 0], [6, 0], [0, 6], [6, 6], [-6, 0], [-6, 6]]}


def mean_distance(q: np.ndarray) -> float:
    d = np.linalg.norm(q[:, None] - q[None], axis=-1)
    return float(d[np.triu_indices(len(q), 1)].mean())


@effect("silent:d0_m")
def test_a_larger_d0_spreads_the_team() -> None:
    spread = [mean_distance(ran(changed(TEAM, strategy__params__d0_m=d0)).positions[-1])
              for d0 in (5.0, 8.0, 11.0)]  # fmt: skip
    assert spread[0] < spread[1] < spread[2], spread
    assert spread[0] < 7.0 < 11.0 < spread[2]


@effect("silent:cost")
def test_farthest_cost_pulls_the_team_together() -> None:
    desired = mean_distance(ran(changed(TEAM, strategy__params__d0_m=11.0)).positions[-1])
    farthest = ran(changed(TEAM, strategy__params__cost="farthest")).positions[-1]
    assert mean_distance(farthest) < 0.7 * desired


@effect("silent:gamma")
def test_gamma_scales_the_followers_steps() -> None:
    moved = {}
    for gamma in (0.05, 0.5):
        r = ran(changed(TEAM, strategy__params__gamma=gamma), max_steps=1)
        step = np.linalg.norm(r.positions[1] - r.positions[0], axis=1)
        moved[gamma] = np.delete(step, r.built.strategy.leader).mean()
    assert moved[0.5] > 2 * moved[0.05] > 0


@effect("silent:leader")
def test_the_leader_is_the_robot_named() -> None:
    for leader in (0, 3):
        data = changed(SILENT, team__init=START, strategy__params__leader=leader,
                       strategy__params__gamma=0.01)  # fmt: skip
        r = ran(data, max_steps=4)
        travel = np.linalg.norm(r.positions[-1] - r.positions[0], axis=1)
        assert r.built.strategy.leader == leader
        assert travel[leader] > 2.0 > 2 * np.delete(travel, leader).max(), travel


@effect("silent:trajectory.waypoints", "silent:trajectory.kind")
def test_the_leader_follows_the_waypoints() -> None:
    for end in ([12.0, 0.0], [0.0, -12.0]):
        path = {"kind": "waypoints", "waypoints": [[0, 0], end], "speed_mps": 1.0}
        r = ran(changed(SILENT, team__init=START, strategy__params__trajectory=path), 20)
        leader = r.positions[-1, r.built.strategy.leader]
        assert np.linalg.norm(leader - end) <= 0.5 + 1e-9
        assert r.metrics["leader_reached_goal"]


@effect("silent:trajectory.function", "silent:trajectory.kind")
def test_a_function_of_time_leads(monkeypatch: pytest.MonkeyPatch) -> None:
    user_module = types.ModuleType("leader_paths")  # a module the user has loaded
    user_module.leader_circle = leader_circle
    monkeypatch.setitem(sys.modules, "leader_paths", user_module)
    path = {"kind": "function", "function": "leader_paths:leader_circle"}
    pts = {"kind": "positions", "positions": [[10, 0], [4, 0], [10, 6], [4, 6]]}
    r = ran(changed(SILENT, team__n_robots=4, team__init=pts, strategy__params__trajectory=path), 5)
    leader = r.built.strategy.leader
    assert leader == 0  # the robot nearest the function's value at t = 0
    want = [10 * np.cos(0.25), 10 * np.sin(0.25)]  # t = 5 s
    np.testing.assert_allclose(r.positions[-1, leader], want, atol=1e-6)


@effect("silent:trajectory.speed_mps")
def test_speed_sets_the_leaders_pace() -> None:
    travel = {}
    for speed in (0.5, 1.5):
        path = {"kind": "waypoints", "waypoints": [[0, 0], [60, 0]], "speed_mps": speed}
        r = ran(changed(SILENT, team__init=START, strategy__params__trajectory=path), 4)
        travel[speed] = r.metrics["leader_travel_m"]
    assert travel[0.5] == pytest.approx(2.0, rel=1e-6)
    assert travel[1.5] == pytest.approx(6.0, rel=1e-6)


@effect("silent:trajectory.goal_tolerance_m")
def test_a_wider_goal_tolerance_ends_the_run_sooner() -> None:
    steps = {}
    for tol in (0.2, 3.0):
        path = {"kind": "waypoints", "waypoints": [[0, 0], [10, 0]], "goal_tolerance_m": tol}
        r = ran(changed(SILENT, team__init=START, strategy__params__trajectory=path), 30)
        steps[tol] = r.result.steps
        assert r.metrics["leader_reached_goal"]
    assert steps[3.0] < steps[0.2] < 30


@effect("silent:max_speed_mps")
def test_max_speed_caps_every_step() -> None:
    for cap in (0.3, 0.8):  # m/s, with 0.5 s steps
        r = ran(changed(TEAM, sim__dt_s=0.5, strategy__params__max_speed_mps=cap), max_steps=10)
        step = np.linalg.norm(np.diff(r.positions, axis=0), axis=2)
        assert step.max() <= cap * 0.5 + 1e-9
        assert step.max() > 0.9 * cap * 0.5
    free = ran(changed(TEAM, sim__dt_s=0.5), max_steps=10)
    assert np.linalg.norm(np.diff(free.positions, axis=0), axis=2).max() > 0.5


@effect("silent:min_separation_m")
def test_min_separation_keeps_followers_apart() -> None:
    close = min(
        r.min_distance_m for r in ran(changed(TEAM, strategy__params__d0_m=5.0)).result.records
    )
    apart = changed(TEAM, strategy__params__d0_m=5.0, strategy__params__min_separation_m=2.5)
    kept = min(r.min_distance_m for r in ran(apart).result.records)
    assert close < 1.0 and kept > 1.5  # measured with noise: kept to the bound's margin


@effect("silent:search_directions")
def test_searching_directions_blocks_the_leader_less() -> None:
    on = ran(changed(TEAM, strategy__params__search_directions=True)).metrics
    off = ran(changed(TEAM, strategy__params__search_directions=False)).metrics
    assert on["leader_blocked_steps"] < off["leader_blocked_steps"]
    assert on["path_progress"] > off["path_progress"]


@effect("silent:robust")
def test_robust_steps_keep_the_true_graph_connected_under_bound_noise() -> None:
    broken = {}
    for robust in (True, False):
        broken[robust] = 0
        for seed in range(10):
            data = changed(
                SILENT, seed=seed, team__n_robots=8, sim__max_steps=30,
                team__init={"kind": "random_connected", "spacing_m": 11.0, "min_separation_m": 2.0},
                sensing={"range_m": 12.0, "radial_error_m": 0.5, "angular_error_deg": 60.0,
                         "noise": "bound"},
                strategy__params__robust=robust, strategy__params__d0_m=11.5,
                strategy__params__gamma=0.5, strategy__params__trajectory__speed_mps=3.0,
            )  # fmt: skip
            broken[robust] += not ran(data).result.connected_all_steps
    assert broken[True] == 0 and broken[False] >= 3, broken
