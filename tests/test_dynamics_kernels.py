"""The integrator's compiled kernels give the numpy reference's bits.

:mod:`tether.continuous.connectivity.dynamics_kernels` runs one step of eq. (1) (the robot
model of :mod:`tether.continuous.connectivity.robot`, the world's box), the displacement
rule and the sub-step's stiffness and energy terms; the references are
:func:`~tether.continuous.connectivity.robot.damped_step`,
:func:`~tether.continuous.connectivity.robot.dissipation`,
:func:`~tether.continuous.connectivity.robot.stay_inside`,
:func:`~tether.continuous.connectivity.dynamics.displacement_step` and
:func:`~tether.continuous.connectivity.dynamics.substep_terms`. Which path runs is pinned
in every test.
"""

from __future__ import annotations

import numpy as np
import pytest

from tether import jit
from tether.continuous.connectivity.dynamics import displacement_step, robot_step, substep_terms
from tether.continuous.connectivity.robot import RobotModel, damped_step, stay_inside

pytestmark = pytest.mark.skipif(not jit.available(), reason="needs numba")


def _team(rng: np.random.Generator, n: int, dim: int) -> tuple[np.ndarray, ...]:
    q = rng.uniform(-5, 5, (n, dim))
    v = rng.normal(0, 2, (n, dim))
    f = rng.normal(0, 10, (n, dim)) * rng.uniform(0, 1, (n, 1))
    return q, v, f


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("vmax", [np.inf, 3.0])
@pytest.mark.parametrize("seed", range(4))
def test_robot_step_is_the_same_with_and_without_kernels(dim: int, vmax: float, seed: int):
    rng = np.random.default_rng(seed)
    q, v, f = _team(rng, 35, dim)
    robot = RobotModel(float(rng.uniform(0.5, 3)), float(rng.uniform(0, 3)), vmax, 0.25)
    h = float(rng.uniform(1e-4, 0.1))
    box = np.array([[-4.0] * dim, [4.0] * dim])
    for corners in (None, box):
        with jit.using(False):
            want = robot_step(q, v, f, h, robot, corners, 0.5)
        with jit.using(True):
            got = robot_step(q, v, f, h, robot, corners, 0.5)
        for x, y in zip(got, want, strict=True):
            np.testing.assert_array_equal(x, y)
    if not np.isfinite(vmax):  # the printed formula of eq. (1) with linear damping
        m, b = robot.mass_kg, robot.damping_ns_per_m
        _, v1, *_ = robot_step(q, v, f, h, robot)
        np.testing.assert_allclose(v1, (m * v + h * f) / (m + h * b), rtol=1e-15)


def test_the_box_stops_only_the_wall_component_and_counts_it() -> None:
    rng = np.random.default_rng(7)
    box = np.array([[0.0, 0.0], [10.0, 10.0]])
    robot = RobotModel(1.0, 2.0)
    for path in (False, True):
        with jit.using(path):
            q = rng.uniform(-1.0, 11.0, (20, 2))  # some start outside the margin
            v = rng.normal(0, 3, (20, 2))
            f = rng.normal(0, 30, (20, 2))
            q1, v1, contacts, _, _ = robot_step(q, v, f, 0.2, robot, box, 0.75)
            q_free, v_free = damped_step(q, v, f, 0.2, robot)
            q_ref, v_ref = stay_inside(q, q_free, v_free, box, 0.75)
            np.testing.assert_array_equal(q1, q_ref)
            np.testing.assert_array_equal(v1, v_ref)
            assert contacts == np.count_nonzero(q_free != q_ref) > 0


@pytest.mark.parametrize("seed", range(4))
def test_displacement_and_terms_are_the_same_with_and_without_kernels(seed: int) -> None:
    rng = np.random.default_rng(seed)
    q, v, f = _team(rng, 30, 3)
    q1, v1, f1 = q + 0.01 * v, v + 0.1 * rng.normal(size=v.shape), f + rng.normal(size=f.shape)
    f_c = 0.5 * f
    pairs = np.array([[i, j] for i in range(30) for j in range(i + 1, 30) if (i + j) % 7 == 0])
    with jit.using(False):
        want = (displacement_step(v, f, 1.3, 0.1),
                substep_terms(q, v, q1, v1, f, f1, f_c, pairs, 0.01, 1.3))  # fmt: skip
    with jit.using(True):
        got = (displacement_step(v, f, 1.3, 0.1),
               substep_terms(q, v, q1, v1, f, f1, f_c, pairs, 0.01, 1.3))  # fmt: skip
    assert got[0] == want[0]
    assert tuple(got[1]) == tuple(want[1])


def test_terms_against_their_definitions() -> None:
    """An independent computation of each term (plain loops over robots)."""
    rng = np.random.default_rng(3)
    n, m, h = 6, 1.7, 0.02
    q, v, f = _team(rng, n, 3)
    q1, v1, f1 = q + h * v, v + rng.normal(size=v.shape), f + rng.normal(size=f.shape)
    f_c = rng.normal(size=f.shape)
    pairs = np.array([[0, 1], [1, 2], [3, 4]])
    for path in (False, True):
        with jit.using(path):
            omega2, jump, work, kinetic, speed, accel = substep_terms(q, v, q1, v1, f, f1, f_c,
                                                                pairs, h, m)  # fmt: skip
        nbrs = {i: {i} for i in range(n)}
        for i, j in pairs:
            nbrs[i].add(j)
            nbrs[j].add(i)
        want = max(
            np.linalg.norm(f1[i] - f[i]) / (m * max(np.linalg.norm(q1[j] - q[j]) for j in nbrs[i]))
            for i in range(n)
        )
        assert omega2 == pytest.approx(want, rel=1e-12)
        assert jump == pytest.approx(max(np.linalg.norm(f1 - f, axis=1)), rel=1e-15)
        assert work == pytest.approx(float(np.sum((f - f_c) * (q1 - q))), rel=1e-12)
        assert kinetic == pytest.approx(0.5 * m * float(np.sum(v1**2) - np.sum(v**2)), rel=1e-12)
        assert speed == pytest.approx(max(np.linalg.norm(x) for x in v1), rel=1e-15)
        assert accel == pytest.approx(max(np.linalg.norm(v1 - v, axis=1)) / h, rel=1e-15)
