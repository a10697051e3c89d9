"""The virtual point of the traveling force (continuous-connectivity paper, Sec. 3.6, eq. 3).

Oracles: finite differences of the point's position and velocity in time, the
centripetal acceleration v^2 / R on a circle, and the arc length it covers.
"""

from __future__ import annotations

import numpy as np
import pytest

from tether.paths.bspline import SplinePath, smooth_path
from tether.paths.virtual_point import VirtualPoint, virtual_state

H_S = 1e-5


def random_path(seed: int, dim: int) -> SplinePath:
    rng = np.random.default_rng(seed)
    return smooth_path(np.cumsum(rng.normal(size=(8, dim)), axis=0) * 2.0, tolerance_m=0.3)


def finite_differences(vp: VirtualPoint, t: float) -> tuple[np.ndarray, np.ndarray]:
    before, after = vp.at(t - H_S), vp.at(t + H_S)
    vel = (after.position_m - before.position_m) / (2 * H_S)
    acc = (after.velocity_mps - before.velocity_mps) / (2 * H_S)
    return vel, acc


@pytest.mark.parametrize("dim", [2, 3])
def test_velocity_and_acceleration_are_the_time_derivatives(dim):
    for seed in range(3):
        path = random_path(100 * dim + seed, dim)
        vp = VirtualPoint(path, v_cruise_mps=3.0)
        t_end = path.length_m / 3.0
        for t in np.linspace(0.05, 0.95, 15) * t_end:
            state = vp.at(t)
            assert state.s_m == pytest.approx(3.0 * t, rel=1e-12)
            assert np.linalg.norm(state.velocity_mps) == pytest.approx(3.0, rel=1e-12)
            vel, acc = finite_differences(vp, t)
            np.testing.assert_allclose(state.velocity_mps, vel, atol=1e-6)
            scale = 1.0 + np.abs(state.acceleration_mps2).max()
            np.testing.assert_allclose(state.acceleration_mps2, acc, atol=1e-4 * scale)


def test_centripetal_acceleration_on_a_circle():
    radius, v = 4.0, 2.0
    th = np.linspace(0.0, 1.5 * np.pi, 80)
    path = smooth_path(radius * np.c_[np.cos(th), np.sin(th)], tolerance_m=0.002)
    for s in np.linspace(1.0, path.length_m - 1.0, 12):
        state = virtual_state(path, s, v)
        acc = state.acceleration_mps2
        np.testing.assert_allclose(np.linalg.norm(acc), v * v / radius, rtol=0.05)
        inward = -state.position_m / np.linalg.norm(state.position_m)
        assert acc @ inward == pytest.approx(np.linalg.norm(acc), rel=1e-2)
        assert abs(acc @ state.velocity_mps) < 1e-9  # constant speed: no tangential part


def test_stops_at_the_end():
    path = random_path(7, 3)
    vp = VirtualPoint(path, v_cruise_mps=2.0, s0_m=0.5 * path.length_m)
    t_end = 0.5 * path.length_m / 2.0
    for t in (t_end, t_end + 0.1, 10 * t_end):
        state = vp.at(t)
        assert state.s_m == path.length_m
        np.testing.assert_allclose(state.position_m, path.end, atol=1e-12)
        np.testing.assert_array_equal(state.velocity_mps, 0.0)
        np.testing.assert_array_equal(state.acceleration_mps2, 0.0)
    assert vp.at(-1.0).s_m == pytest.approx(0.5 * path.length_m)


def test_braking_profile():
    path = random_path(9, 2)
    v, a = 3.0, 2.0
    vp = VirtualPoint(path, v_cruise_mps=v, stop_decel_mps2=a)
    brake_s = path.length_m - v * v / (2 * a)
    t_brake = brake_s / v
    t_stop = t_brake + v / a
    # cruising, braking (speed sqrt(2 a (L - s))), then stopped exactly at t_stop
    for t in np.concatenate(
        [np.linspace(0.1, 0.9, 5) * t_brake, t_brake + np.array([0.2, 0.7, 1.3])]
    ):
        state = vp.at(t)
        speed = min(v, np.sqrt(2 * a * (path.length_m - state.s_m)))
        assert np.linalg.norm(state.velocity_mps) == pytest.approx(speed, rel=1e-9)
        vel, acc = finite_differences(vp, t)
        np.testing.assert_allclose(state.velocity_mps, vel, atol=1e-6)
        scale = 1.0 + np.abs(state.acceleration_mps2).max()
        np.testing.assert_allclose(state.acceleration_mps2, acc, atol=1e-4 * scale)
        if t > t_brake:  # tangential deceleration a
            tangent = state.velocity_mps / np.linalg.norm(state.velocity_mps)
            assert state.acceleration_mps2 @ tangent == pytest.approx(-a, rel=1e-6)
    assert vp.at(t_stop - 1e-3).s_m < path.length_m
    stopped = vp.at(t_stop)
    assert stopped.s_m == path.length_m
    np.testing.assert_array_equal(stopped.velocity_mps, 0.0)
    # starting inside the braking zone: slower from the start, stops at the same place
    late = VirtualPoint(path, v, s0_m=path.length_m - 0.5, stop_decel_mps2=a)
    assert np.linalg.norm(late.at(0.0).velocity_mps) == pytest.approx(np.sqrt(2 * a * 0.5))
    assert late.at(np.sqrt(2 * 0.5 / a)).s_m == path.length_m


def test_polyline_and_bad_arguments():
    path = SplinePath.polyline([[0.0, 0.0], [2.0, 0.0], [2.0, 2.0]])
    state = virtual_state(path, 1.0, 1.5)
    np.testing.assert_allclose(state.velocity_mps, [1.5, 0.0])
    np.testing.assert_array_equal(state.acceleration_mps2, 0.0)
    with pytest.raises(ValueError):
        virtual_state(path, 1.0, -1.0)
    with pytest.raises(ValueError):
        virtual_state(path, 1.0, 1.0, stop_decel_mps2=0.0)
