"""The laws of Algorithm 2 (eqs. (3)-(16)) against independent oracles."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from tether import jit
from tether.comm import CommParams, MessageLayer
from tether.continuous.exploration.consensus import EfficiencyConsensus
from tether.continuous.exploration.reference_filter import PAPER_GAINS, ReferenceFilter
from tether.continuous.exploration.tracking import PathSet, TrackedPath
from tether.continuous.exploration.travel import (
    alignment,
    anchor_force,
    anchor_potential,
    efficiency,
    rho,
    travel_force,
)
from tether.paths.bspline import SplinePath, smooth_path

GRID = np.linspace(0.0, 1.0, 41)


# ------------------------------------------------------------------ rho (Sec. 3.7)
def test_rho_is_one_and_zero_at_the_efficiency_bounds() -> None:
    for theta, sigma in itertools.product(GRID, (1.0, 2.0, 3.0, 6.0)):
        assert rho(theta, 1.0, sigma) == pytest.approx(1.0)  # property 1
        assert rho(theta, 0.0, sigma) == pytest.approx(0.0)  # property 2


def test_rho_monotone_in_efficiency_and_alignment() -> None:
    for sigma in (1.0, 2.0, 3.0, 6.0):
        for theta in GRID:
            assert np.all(np.diff(rho(theta, GRID, sigma)) >= -1e-15)  # property 3
        inner = GRID[1:-1]
        for y in inner:
            vals = rho(GRID, y, sigma)
            if sigma > 1:
                assert np.all(np.diff(vals) > 0)  # property 4: strictly increasing in Theta
            else:
                assert np.allclose(vals, y)  # property 5: sigma = 1 gives Lambda_hat


def test_rho_tends_to_alignment_for_large_sigma() -> None:
    theta = np.linspace(0.05, 0.95, 7)
    for y in (0.2, 0.5, 0.8):
        assert np.allclose(rho(theta, y, 400.0), theta, atol=1e-6)  # property 6


# ------------------------------------------------------------------ Theta, Lambda
def test_alignment_matches_the_cosine_form() -> None:
    rng = np.random.default_rng(0)
    x, y = rng.normal(size=(50, 3)), rng.normal(size=(50, 3))
    angle = np.arccos(np.sum(x * y, 1) / np.linalg.norm(x, axis=1) / np.linalg.norm(y, axis=1))
    assert np.allclose(alignment(x, y), 0.5 * (1 + np.cos(angle)))
    assert alignment(np.zeros((1, 3)), y[:1])[0] == 1.0  # eq. (8): 1 when a vector is zero
    assert alignment(x[:1], -x[:1])[0] == pytest.approx(0.0)


def test_efficiency_shape() -> None:
    x = np.linspace(0, 2, 401)
    lam = efficiency(x, 0.3, 1.2)
    assert np.all(lam[x <= 0.3] == 1.0) and np.all(lam[x >= 1.2] == 0.0)
    assert np.all(np.diff(lam) <= 0)
    mid = efficiency(np.array([0.75]), 0.3, 1.2)[0]
    assert mid == pytest.approx(0.5)  # the cosine step is symmetric


# ------------------------------------------------------------------ anchor (eqs. 5-7)
def test_anchor_force_is_minus_the_gradient_of_the_potential() -> None:
    rng = np.random.default_rng(1)
    rz, kz = 1.8, 2.5
    z = np.array([[3.0, -1.0, 2.0]])
    for _ in range(20):
        d = rng.normal(size=3)
        q = z[0] + d / np.linalg.norm(d) * rng.uniform(0.05, 0.95 * rz)
        f = anchor_force(q[None], z, rz, kz)[0]
        grad = np.zeros(3)
        for k in range(3):
            e = np.zeros(3)
            e[k] = 1e-6
            up = anchor_potential(np.linalg.norm(q + e - z[0]), rz, kz)
            down = anchor_potential(np.linalg.norm(q - e - z[0]), rz, kz)
            grad[k] = (up - down) / 2e-6
        assert np.allclose(f, -grad, rtol=1e-5, atol=1e-7)
    assert anchor_potential(np.array(rz), rz, kz) == np.inf


# ------------------------------------------------------------------ tracking
def _curvy_path(seed: int) -> SplinePath:
    rng = np.random.default_rng(seed)
    pts = np.cumsum(rng.normal(size=(8, 3)) * [3.0, 3.0, 0.5], axis=0)
    return smooth_path(pts)


@pytest.mark.parametrize("seed", range(6))
def test_closest_point_against_brute_force_on_the_spline(seed: int) -> None:
    spline = _curvy_path(seed)
    tracked = TrackedPath.from_spline(spline, spacing_m=0.05)
    s_dense = np.linspace(0, spline.length_m, 20001)
    dense = spline.point(s_dense)
    rng = np.random.default_rng(seed + 100)
    q = dense[rng.integers(len(dense), size=12)] + rng.normal(scale=1.5, size=(12, 3))
    st = PathSet([tracked] * len(q)).states(q, 2.0)
    for k in range(len(q)):
        d = np.linalg.norm(dense - q[k], axis=1)
        assert st.distance_m[k] == pytest.approx(d.min(), abs=2e-3)
        # the minimum is flat: arc lengths within ~0.1 m are as close as the sampling allows
        assert st.s_m[k] == pytest.approx(s_dense[np.argmin(d)], abs=0.15)
        assert st.remaining_m[k] == pytest.approx(spline.length_m - st.s_m[k])


def test_ties_go_to_the_largest_arc_length() -> None:
    """A U-shaped path: a point between its legs is equally close to both."""
    u = SplinePath.polyline(np.array([[0.0, 0, 0], [10, 0, 0], [10, 2, 0], [0, 2, 0]]))
    st = PathSet([TrackedPath.from_spline(u)]).states(np.array([[5.0, 1.0, 0.0]]), 1.0)
    assert st.s_m[0] == pytest.approx(10 + 2 + 5, abs=1e-9)  # the return leg, not the first
    assert np.allclose(st.velocity_mps[0], [-1.0, 0, 0])


def test_virtual_point_velocity_and_acceleration_on_a_circle() -> None:
    theta = np.linspace(0, np.pi, 200)
    circle = smooth_path(np.c_[3 * np.cos(theta), 3 * np.sin(theta), 0 * theta], tolerance_m=1e-4)
    st = PathSet([TrackedPath.from_spline(circle, 0.02)]).states(np.array([[0.0, 2.0, 0.0]]), 2.0)
    assert np.linalg.norm(st.velocity_mps[0]) == pytest.approx(2.0, rel=1e-3)
    centripetal = st.acceleration_mps2[0]
    assert np.linalg.norm(centripetal) == pytest.approx(4.0 / 3.0, rel=2e-2)  # v^2 / R
    assert centripetal @ (-st.point_m[0]) > 0  # towards the centre


def test_travel_force_is_eq3_with_feedforward_and_saturation() -> None:
    tracked = TrackedPath.from_spline(SplinePath.polyline(np.array([[0.0, 0, 0], [20, 0, 0]])))
    st = PathSet([tracked]).states(np.array([[5.0, 0.4, 0.0]]), 3.0)
    q, v = np.array([[5.0, 0.4, 0.0]]), np.array([[2.0, 0.0, 0.0]])
    f = travel_force(q, v, st, kp=4.0, kv=3.0, mass_kg=1.0, damping_ns_per_m=2.0)
    assert np.allclose(f, [[2 * 3.0 + 3 * (3.0 - 2.0), 4 * -0.4, 0.0]])
    small = travel_force(q, v, st, kp=4.0, kv=3.0, damping_ns_per_m=2.0, max_force_n=1.0)
    assert np.linalg.norm(small) == pytest.approx(1.0)
    assert np.allclose(small / np.linalg.norm(small), f / np.linalg.norm(f))


# ------------------------------------------------------------------ consensus (eq. 13)
@pytest.mark.parametrize("loss", [0.0, 0.3])
def test_consensus_tracks_a_constant_prime_efficiency(loss: float) -> None:
    rng = np.random.default_rng(3)
    n = 12
    pairs = np.array([(i, i + 1) for i in range(n - 1)] + [(0, 5), (3, 9)])
    cons = EfficiencyConsensus(n, MessageLayer(n, CommParams(loss), rng), gain_per_s=5.0)
    for _ in range(3000):
        cons.round(pairs, 0.05, prime=7, efficiency=0.8)
        assert np.all((cons.estimate >= 0) & (cons.estimate <= 1))
    assert np.allclose(cons.estimate, 0.8, atol=1e-6)


def test_consensus_uses_only_neighbours() -> None:
    n = 6
    pairs = np.array([(0, 1), (1, 2), (3, 4), (4, 5)])  # two components
    cons = EfficiencyConsensus(n, MessageLayer(n, CommParams(), np.random.default_rng(0)), 5.0)
    for _ in range(500):
        cons.round(pairs, 0.05, prime=0, efficiency=1.0)
    assert np.allclose(cons.estimate[:3], 1.0) and np.allclose(cons.estimate[3:], 0.0)


# ------------------------------------------------------------------ reference filter (eq. 16)
def test_reference_filter_is_the_exact_solution_of_eq16() -> None:
    q0 = np.zeros((1, 1))
    filt = ReferenceFilter(q0, 0.01)
    out = [filt.update(np.ones((1, 1)))[0, 0] for _ in range(60)]
    k1, k2, k3, k4 = PAPER_GAINS

    def rhs(t, x):  # noqa: ANN001, ARG001
        return [x[1], x[2], x[3], -k1 * x[3] - k2 * x[2] - k3 * x[1] + k4 * (1.0 - x[0])]

    ref = solve_ivp(rhs, (0, 0.6), [0, 0, 0, 0], t_eval=np.arange(1, 61) * 0.01, rtol=1e-10,
                    atol=1e-12, method="Radau").y[0]  # fmt: skip
    assert np.allclose(out, ref, atol=1e-8)
    for _ in range(300):  # 3 s more: the reference settles on the input, without overshoot
        out.append(filt.update(np.ones((1, 1)))[0, 0])
    assert out[-1] == pytest.approx(1.0, abs=1e-9)
    assert np.all(np.diff(out) >= -1e-12) and max(out) <= 1.0 + 1e-9


@pytest.mark.skipif(not jit.available(), reason="needs numba")
@pytest.mark.parametrize("dim", [2, 3])
def test_reference_filter_advance_compiled_is_the_numpy_path(dim: int) -> None:
    """The compiled period gives the numpy path's state and peaks bit for bit, and the
    peaks are the largest row norms of the state it reached (an independent max)."""
    rng = np.random.default_rng(dim)
    q0 = rng.normal(0.0, 20.0, (13, dim))
    compiled, reference = ReferenceFilter(q0, 0.1), ReferenceFilter(q0, 0.1)
    for step in range(40):
        q = q0 + rng.normal(0.0, 1.0 + step, q0.shape)
        with jit.using(True):
            got = compiled.advance(q)
        with jit.using(False):
            want = reference.advance(q)
        assert got == want and np.array_equal(compiled.state, reference.state)
        rows = [compiled.state[0] - q, compiled.state[1], compiled.state[2]]
        assert got == pytest.approx([max(float(np.sqrt(r @ r)) for r in x) for x in rows],
                                    rel=1e-15)  # fmt: skip
