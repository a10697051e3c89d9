"""A robot held by an anchor against a large connectivity force, then released.

Three robots in a line 5.3 m apart (``Rs`` = 6 m) are near the barrier: the connectivity
force pulls each end robot inwards with about 160 N, sixteen times the bound of any
traveling force. Both ends are anchors placed on the rim of their ``Rz`` ball where the
paper's anchor force (eq. (7)) balances that pull. Robot 0's stay ends after 0.2 s and it
is released. The stored energy throws it inwards: its speed must stay within the robot
model's bound, and lambda2 positive, with the guard only watching (``detect``).
"""

from __future__ import annotations

import numpy as np
import pytest

from tether.config import scenario_from_dict
from tether.record import TrajectoryRecorder
from tether.runner import build
from tether.sim import simulate

SPACING_M = 5.3


def scenario(targets: list[list[float]], **params: object) -> object:
    positions = [[20.0 + k * SPACING_M, 20.0, 5.0] for k in range(3)]
    queues = [{"robot": 0, "targets": [targets[0]], "stay_s": 0.2},
              {"robot": 2, "targets": [targets[1]], "stay_s": 60.0}]  # fmt: skip
    return scenario_from_dict({
        "name": "release", "seed": 1, "world": {"scene": "free", "dim": 3},
        "sensing": {"range_m": 6.0},
        "team": {"n_robots": 3, "init": {"kind": "positions", "positions": positions}},
        "sim": {"dt_s": 0.1, "max_steps": 60},
        "strategy": {"name": "multi_target", "params": {
            "preset": "outdoor", "max_anchor_force_n": None, **params,
            "targets": {"kind": "fixed", "params": {"queues": queues}}}},
    }, "release.yaml")  # fmt: skip


def held_and_released(**params: object) -> tuple[dict, TrajectoryRecorder, float]:
    probe = build(scenario([[0.0, 20.0, 5.0], [50.0, 20.0, 5.0]], **params))
    s = probe.strategy
    s.reset(probe.world, probe.initial, probe.rng)
    q = probe.initial.positions
    pull = s.connectivity_force(s.evaluate(q)[1])
    pull_n = float(np.linalg.norm(pull[0]))
    p = s.params  # the rim where kz tan(l pi / (2 Rz)) = the pull: the anchor holds
    rim = 2 * p.rz_m / np.pi * np.arctan(pull_n / p.kz_n)
    targets = [(q[0] - [rim, 0, 0]).tolist(), (q[2] + [rim, 0, 0]).tolist()]
    built = build(scenario(targets, **params))
    rec = TrajectoryRecorder(every=1)
    res = simulate(built.world, built.sensor, built.strategy, built.initial, dt_s=0.1,
                   max_steps=60, rng=built.rng, recorder=rec)  # fmt: skip
    return res.strategy_metrics, rec, pull_n


def test_a_released_anchor_stays_within_the_speed_bound_and_connected() -> None:
    m, rec, pull_n = held_and_released()
    assert pull_n > 10 * 10.0  # far beyond any traveling force (max_travel_force_n)
    released = [e["step"] for e in rec.events if e["kind"] == "target_reached"]
    assert released == [2]
    speed = np.array(rec.step_columns()["max_speed_mps"])
    assert speed[:2].max() < 0.1 and speed[3:8].max() > 4.0  # held, then thrown
    assert m["max_speed_mps"] <= m["speed_bound_mps"] == 6.0
    assert m["min_lambda2_weighted"] > 0.01
    assert m["controller_success"] and m["guard_interventions"] == m["safe_set_exits"] == 0
    assert m["anchor_outside_steps"] == 0


def test_without_the_speed_bound_the_same_release_is_faster() -> None:
    """The bound is what keeps the speed in: the paper's point mass goes past it."""
    m, _, _ = held_and_released(max_speed_mps=1000.0)
    assert m["max_speed_mps"] > 6.3
    assert m["controller_success"]


@pytest.mark.parametrize("bound_n", [10.0, 50.0])
def test_a_saturated_anchor_gives_way_and_says_so(bound_n: float) -> None:
    """With ``max_anchor_force_n`` below the pull the anchor cannot hold: it is dragged
    out of its ball (counted) instead of being held at the rim."""
    m, rec, pull_n = held_and_released(max_anchor_force_n=bound_n)
    assert pull_n > bound_n
    assert m["anchor_outside_steps"] > 0
    assert m["max_speed_mps"] <= m["speed_bound_mps"]
    assert m["controller_success"]
