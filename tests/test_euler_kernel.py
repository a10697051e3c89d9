"""The compiled sub-step of eq. (1) gives the numpy reference's bits.

:func:`tether.continuous.force_kernels.euler_kernel` is the integrator's update when the
kernels run (and :func:`tether.continuous.dynamics.semi_implicit_euler` calls it for team
arrays then); the reference is the numpy expression, with
:func:`~tether.continuous.dynamics.stay_inside` for the world's box.
"""

from __future__ import annotations

import numpy as np
import pytest

from tether import jit
from tether.continuous.dynamics import semi_implicit_euler, stay_inside

pytestmark = pytest.mark.skipif(not jit.available(), reason="needs numba")


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("seed", range(5))
def test_semi_implicit_euler_is_the_same_with_and_without_kernels(dim: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    q = rng.uniform(-50, 50, (35, dim))
    v = rng.normal(0, 2, (35, dim))
    f = rng.normal(0, 10, (35, dim)) * rng.uniform(0, 1, (35, 1))
    h, m, b = float(rng.uniform(1e-4, 0.1)), float(rng.uniform(0.5, 3)), float(rng.uniform(0, 3))
    with jit.using(False):
        want = semi_implicit_euler(q, v, f, h, m, b)
        by_hand = ((m * v + h * f) / (m + h * b),)  # the printed formula
    with jit.using(True):
        got = semi_implicit_euler(q, v, f, h, m, b)
    np.testing.assert_array_equal(want[1], by_hand[0])
    for x, y in zip(got, want, strict=True):
        np.testing.assert_array_equal(x, y)


@pytest.mark.parametrize("dim", [2, 3])
def test_euler_kernel_in_a_box_is_euler_then_stay_inside(dim: int) -> None:
    from tether.continuous.force_kernels import euler_kernel

    rng = np.random.default_rng(7)
    box = np.array([[0.0] * dim, [10.0] * dim])
    for _ in range(50):
        q = rng.uniform(-1.0, 11.0, (20, dim))  # some robots start outside the margin
        v = rng.normal(0, 3, (20, dim))
        f = rng.normal(0, 30, (20, dim))
        with jit.using(False):
            q_ref, v_ref = stay_inside(q, *semi_implicit_euler(q, v, f, 0.2, 1.0, 2.0), box, 0.75)
        q_k, v_k = euler_kernel(q, v, f, 0.2, 1.0, 2.0, box, 0.75)
        np.testing.assert_array_equal(q_k, q_ref)
        np.testing.assert_array_equal(v_k, v_ref)
        assert np.any(v_k == 0.0)  # some hit a wall and stopped there
