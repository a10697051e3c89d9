"""The robot of eq. (1): the speed bound holds for any force, the damping only dissipates.

Oracles are the step's own equation solved another way (bisection on the scalar speed
equation) and the energy balance of one step written out by hand.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from tether.continuous.connectivity.robot import RobotModel, damped_step, dissipation

finite = st.floats(-1e6, 1e6, allow_nan=False)


@settings(max_examples=200, deadline=None)
@given(v=st.lists(finite, min_size=3, max_size=3), f=st.lists(finite, min_size=3, max_size=3),
       h=st.floats(1e-6, 1.0), vmax=st.floats(0.1, 50.0), beta=st.floats(0.0, 5.0))  # fmt: skip
def test_no_force_and_no_step_length_exceeds_the_speed_bound(v, f, h, vmax, beta) -> None:
    robot = RobotModel(1.0, 2.0, vmax, beta)
    v0 = np.asarray([v]) * min(1.0, 0.999 * vmax / max(np.linalg.norm(v), 1e-300))
    _, v1 = damped_step(np.zeros((1, 3)), v0, np.asarray([f]), h, robot)
    assert np.linalg.norm(v1) <= vmax * (1 + 4e-16)  # beta = 0: the bound is a clip
    assert np.all(np.isfinite(v1))


@pytest.mark.parametrize("beta", [0.0, 0.25, 3.0])
def test_the_new_speed_solves_the_step_equation(beta: float) -> None:
    """``(m + h B(s)) s = |m v + h f|`` with ``B(s) = b + beta / (v_max - s)``, by bisection."""
    rng = np.random.default_rng(1)
    robot = RobotModel(1.4, 2.0, 6.0, beta)
    m, b, vmax = robot.mass_kg, robot.damping_ns_per_m, robot.max_speed_mps
    for _ in range(100):
        v = rng.normal(0, 2, (1, 3))
        v *= min(1.0, 5.9 / np.linalg.norm(v))
        f, h = rng.normal(0, 30, (1, 3)), float(rng.uniform(1e-3, 0.2))
        _, v1 = damped_step(np.zeros((1, 3)), v, f, h, robot)
        p = np.linalg.norm(m * v + h * f)
        lo, hi = 0.0, vmax
        for _ in range(200):
            s = 0.5 * (lo + hi)
            lhs = (m + h * b) * s + h * beta * s / (vmax - s) if s < vmax else np.inf
            lo, hi = (s, hi) if lhs < p else (lo, s)
        assert np.linalg.norm(v1) == pytest.approx(0.5 * (lo + hi), rel=1e-9, abs=1e-12)
        np.testing.assert_allclose(v1 / np.linalg.norm(v1), (m * v + h * f) / p, rtol=1e-12)


def test_the_step_keeps_the_energy_balance_and_dissipation_is_what_the_damping_took() -> None:
    """``dKE = f . dq - h B |v+|^2 - m |dv|^2 / 2`` for every step (semi-implicit Euler)."""
    rng = np.random.default_rng(2)
    for vmax in (np.inf, 4.0):
        robot = RobotModel(0.8, 1.5, vmax, 0.25)
        m = robot.mass_kg
        for _ in range(50):
            v = rng.normal(0, 1, (5, 3))
            f, h = rng.normal(0, 8, (5, 3)), float(rng.uniform(1e-3, 0.3))
            q1, v1 = damped_step(np.zeros((5, 3)), v, f, h, robot)
            diss, limit = dissipation(v, f, h, robot)
            by_hand = h * float(np.sum(robot.damping(np.linalg.norm(v1, axis=1))
                                       * np.sum(v1 * v1, axis=1)))  # fmt: skip
            assert diss == pytest.approx(by_hand, rel=1e-9)
            assert (limit == 0.0) == (not np.isfinite(vmax))
            kinetic = 0.5 * m * float(np.sum(v1 * v1) - np.sum(v * v))
            rhs = float(np.sum(f * q1)) - diss - 0.5 * m * float(np.sum((v1 - v) ** 2))
            assert kinetic == pytest.approx(rhs, rel=1e-9, abs=1e-9)


def test_below_the_bound_the_speed_limit_costs_little_at_cruise() -> None:
    """At half the top speed the speed-limiting damping adds beta N: 4 % of the linear
    drag of the outdoor preset (b = 2, v_max = 6, cruise 3 m/s)."""
    robot = RobotModel(1.0, 2.0, 6.0, 0.25)
    b_cruise = float(robot.damping(np.array(3.0)))
    assert (b_cruise - 2.0) * 3.0 == pytest.approx(0.25)
    assert (b_cruise - 2.0) / 2.0 < 0.05


@pytest.mark.parametrize("kw", [{"mass_kg": 0}, {"damping_ns_per_m": -1}, {"max_speed_mps": 0},
                                {"speed_damping_n": -0.1}])  # fmt: skip
def test_unphysical_models_are_refused(kw: dict) -> None:
    with pytest.raises(ValueError):
        RobotModel(**kw)
