"""The robot model of eq. (1), the integrator's step rule and the guard, in ``connectivity``
and ``multi_target`` (``docs/continuous.md``: "Robot model", "Integrator", "Guard").

The ``connectivity`` runs drift the whole row with one constant force and set
``lambda2_null`` below the row's lambda2, so the connectivity force is zero and every
robot is the point mass of eq. (1) alone: its terminal speed ``s`` solves
``F = b s + beta s / (v_max - s)`` (the damping ``B(s) s``), an oracle for ``b``,
``v_max`` and ``beta``.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

from _continuous_runs import STRATEGIES, both, columns, moved_m, pulled, run, scenario
from _parameters import effect

BOTH = pytest.mark.parametrize("strategy", STRATEGIES)
DRIFT_N = 3.0
DRIFT = {"kind": "constant", "forces": [[DRIFT_N, 0.0]], "magnitude_n": DRIFT_N}


def drift(steps: int = 40, **params: object) -> tuple[dict, np.ndarray]:
    """The row drifting under 3 N per robot, no connectivity force: (metrics, speeds)."""
    r = run(scenario("connectivity", external=DRIFT, lambda2_null=0.1, **params), steps)
    return r.metrics, columns(r)["max_speed_mps"]


def terminal_mps(force_n: float, b: float = 2.0, v_max: float = 6.0, beta: float = 0.25) -> float:
    """The speed at which the damping ``B(s) s`` of the robot model balances ``force_n``."""
    return brentq(lambda s: b * s + beta * s / (v_max - s) - force_n, 0.0, v_max * (1 - 1e-12))


def prime_travel_m(r) -> np.ndarray:  # noqa: ANN001
    """Robot 3's (MT's traveler's) distance from its start at every recorded step."""
    return np.linalg.norm(r.positions[:, 3] - r.positions[0, 3], axis=1)


# -- mass ------------------------------------------------------------------------------------


@effect("connectivity:mass_kg")
def test_a_heavier_robot_gathers_speed_more_slowly_to_the_same_terminal_speed() -> None:
    for mass in (1.0, 4.0):
        m, speed = drift(40, mass_kg=mass, speed_damping_n=0.0)
        b, tau = 2.0, mass / 2.0  # m x'' = F - b x': v(t) = F/b (1 - exp(-t / tau))
        assert speed[10] == pytest.approx(DRIFT_N / b * (1 - np.exp(-1.0 / tau)), rel=0.08)
    light, heavy = drift(10)[1], drift(10, mass_kg=4.0)[1]
    assert heavy[-1] < 0.6 * light[-1]
    assert drift(150, mass_kg=4.0)[1][-1] == pytest.approx(terminal_mps(DRIFT_N), rel=0.01)


@effect("multi_target:mass_kg")
def test_a_heavier_prime_falls_behind_under_the_same_bounded_traveling_force() -> None:
    light = prime_travel_m(run(pulled("multi_target"), 40))
    heavy = prime_travel_m(run(pulled("multi_target", mass_kg=4.0), 40))
    assert heavy[20] < 0.75 * light[20] and heavy[-1] < light[-1]


# -- damping ---------------------------------------------------------------------------------


@effect("connectivity:damping_ns_per_m")
def test_damping_sets_the_terminal_speed_under_a_force() -> None:
    for b in (2.0, 6.0):
        m, speed = drift(60, damping_ns_per_m=b)
        assert speed[-1] == pytest.approx(terminal_mps(DRIFT_N, b=b), rel=0.01)
    assert drift(60, damping_ns_per_m=6.0)[1][-1] < 0.4 * drift(60)[1][-1]


@effect("multi_target:damping_ns_per_m")
def test_damping_slows_the_dragged_robots_but_not_the_prime_whose_feed_forward_carries_it() -> None:
    """``f_travel`` holds ``B v_gamma`` (docs/multi_target.md, "Feed-forward of the damping"):
    the prime cruises at ``v_cruise`` whatever ``B``; the connectors it drags move less."""
    runs = {b: run(pulled("multi_target", damping_ns_per_m=b, v_cruise_mps=1.0), 80)
            for b in (2.0, 6.0)}  # fmt: skip
    for r in runs.values():
        assert r.metrics["max_speed_mps"] == pytest.approx(1.0, abs=0.08)
    assert moved_m(runs[6.0])[0] < 0.4 * moved_m(runs[2.0])[0]  # the rear connector
    assert moved_m(runs[6.0])[3] > 0.85 * moved_m(runs[2.0])[3]  # the prime


# -- the speed bound -------------------------------------------------------------------------


@effect("connectivity:max_speed_mps")
def test_a_lower_top_speed_caps_the_run_and_costs_speed_limit_work() -> None:
    free, capped = drift(40)[0], drift(40, max_speed_mps=1.0)[0]
    assert free["speed_bound_mps"] == 6.0 and capped["speed_bound_mps"] == 1.0
    assert capped["max_speed_mps"] == pytest.approx(terminal_mps(DRIFT_N, v_max=1.0), rel=0.01)
    assert capped["max_speed_mps"] < 1.0 < free["max_speed_mps"]
    assert capped["speed_limit_work_j"] > 5 * free["speed_limit_work_j"]


@effect("multi_target:max_speed_mps")
def test_a_top_speed_near_cruise_slows_the_prime_and_costs_speed_limit_work() -> None:
    free = run(pulled("multi_target"), 80).metrics
    capped = run(pulled("multi_target", max_speed_mps=3.3), 80).metrics  # v_cruise = 3
    assert free["speed_bound_mps"] == 6.0 and capped["speed_bound_mps"] == 3.3
    assert capped["max_speed_mps"] < free["max_speed_mps"] < 3.3
    assert capped["speed_limit_work_j"] > 2 * free["speed_limit_work_j"]


@effect("connectivity:speed_damping_n")
def test_speed_damping_brakes_below_the_bound_and_zero_is_a_hard_clip() -> None:
    speeds = {}
    for beta in (0.0, 0.25, 2.0):
        m = drift(40, max_speed_mps=1.0, speed_damping_n=beta)[0]
        speeds[beta] = m["max_speed_mps"]
        if beta > 0:
            assert speeds[beta] == pytest.approx(terminal_mps(DRIFT_N, 2.0, 1.0, beta), rel=0.01)
    assert speeds[0.0] == pytest.approx(1.0, abs=1e-12)  # clipped at v_max, F/b = 1.5
    assert speeds[2.0] < speeds[0.25] < speeds[0.0]
    assert drift(40, speed_damping_n=0.0)[0]["speed_limit_work_j"] < 1e-9  # rounding only


@effect("multi_target:speed_damping_n")
def test_speed_damping_slows_the_prime_below_its_bound() -> None:
    soft = run(pulled("multi_target", speed_damping_n=0.05), 60).metrics
    hard = run(pulled("multi_target", speed_damping_n=5.0), 60).metrics
    assert hard["max_speed_mps"] < 0.9 * soft["max_speed_mps"]  # the feedback fights it
    assert hard["speed_limit_work_j"] > 10 * soft["speed_limit_work_j"]


# -- the step rule ---------------------------------------------------------------------------


@BOTH
@effect(*both("max_step_fraction"))
def test_a_smaller_step_fraction_takes_more_shorter_sub_steps(strategy: str) -> None:
    coarse = run(pulled(strategy), 40).metrics
    fine = run(pulled(strategy, max_step_fraction=0.02), 40).metrics
    assert fine["substeps"] > 2.5 * coarse["substeps"]
    assert fine["min_substep_s"] < coarse["min_substep_s"]
    # the same motion, resolved more finely
    assert fine["min_lambda2_weighted"] == pytest.approx(coarse["min_lambda2_weighted"], rel=0.05)


# -- the guard -------------------------------------------------------------------------------

#: the decentralized estimator with one round per sub-step and a 10-round warm-up cannot
#: follow the pulled team: within 2.5 s its force lets the team leave the safe set
LAGGING = {"eigensolver": "estimator", "estimator": {"rounds_per_substep": 1, "warmup_rounds": 10}}


def lagging(strategy: str, **params: object):  # noqa: ANN201
    return run(pulled(strategy, **LAGGING, **params), 25)


@BOTH
@effect(*both("guard"))
def test_detect_counts_the_exits_enforce_prevents_them_off_measures_nothing(strategy: str) -> None:
    detect, enforce, off = (lagging(strategy, guard=g) for g in ("detect", "enforce", "off"))
    d, e, o = detect.metrics, enforce.metrics, off.metrics
    assert d["safe_set_exits"] > 0 and d["guard_interventions"] == 0
    assert d["min_lambda2_weighted"] == 0.0 and d["controller_success"] is False
    assert e["safe_set_exits"] == 0 and e["guard_interventions"] > 0
    assert e["min_lambda2_weighted"] > 0.0 and e["controller_success"] is False
    np.testing.assert_array_equal(off.positions, detect.positions)  # off only stops counting
    assert o["safe_set_exits"] == 0 and o["controller_success"] is None
    assert columns(detect)["safe_set_exits_total"][-1] == d["safe_set_exits"]


@BOTH
@effect(*both("keep_fraction"))
def test_enforce_keeping_more_of_the_margin_intervenes_more(strategy: str) -> None:
    loose = lagging(strategy, guard="enforce", keep_fraction=0.0).metrics
    strict = lagging(strategy, guard="enforce", keep_fraction=0.9).metrics
    assert strict["guard_interventions"] > loose["guard_interventions"] > 0
    assert strict["min_lambda2_weighted"] >= loose["min_lambda2_weighted"] > 0
    # it is the enforcing guard's share: detect moves the team the same whatever it is
    a, b = (lagging(strategy, keep_fraction=k).positions for k in (0.0, 0.9))
    np.testing.assert_array_equal(a, b)
