"""Algorithm 2's forces and gains in ``multi_target`` (eqs. (3)-(15) of the
continuous-connectivity paper; ``docs/multi_target.md``), set from a scenario.

Runs use the row of ``_continuous_runs``. In :func:`two_travelers` robot 0 (target 20 m
behind the row) is elected prime and robot 3 (target 40 m ahead) is a secondary
traveler whose traveling force opposes its connectivity force (``Theta`` near 0): eqs.
(14)-(15) scale it by ``rho = Lambda_hat^sigma``, so the more it is throttled, the more
the prime drags it backwards and the farther the prime gets. The laws themselves are
checked on the strategy ``build`` made (:func:`traveling_forces` with its parameters).
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from _continuous_runs import FAR_TARGET, columns, moved_m, pulled, run, scenario, started
from _parameters import effect
from tether.continuous.exploration.motion import traveling_forces
from tether.continuous.exploration.roles import PRIME


def two_travelers(**params: Any) -> dict[str, Any]:
    data = scenario("multi_target", **params)
    data["strategy"]["params"]["targets"]["params"]["queues"] = [
        {"robot": 0, "targets": [[-20.0, 0.0, 5.0]], "stay_s": 1.0},
        {"robot": 3, "targets": [FAR_TARGET], "stay_s": 1.0},
    ]
    return data


def tug(steps: int = 60, **params: Any) -> tuple[float, float, np.ndarray]:
    """(the prime's travel, the secondary's displacement along +x towards its target, the
    prime's efficiency per step) in :func:`two_travelers`."""
    r = run(two_travelers(**params), steps)
    assert columns(r)["prime"][-1] == 0  # robot 0 is the prime
    return (
        moved_m(r)[0],
        float(r.positions[-1, 3, 0] - r.positions[0, 3, 0]),
        columns(r)["prime_efficiency"],
    )


def travel_law(**params: Any) -> tuple[Any, np.ndarray, np.ndarray, Any]:
    """The strategy built with ``params`` and reset (robot 3 a secondary on its path to
    the far target), the row, the path state of robot 3 at ``q``, and a force function
    ``f(q, v, f_lambda, lambda_hat)`` -> robot 3's ``f_i`` (Algorithm 2)."""
    s, q = started(scenario("multi_target", **params))
    trav, paths = s.planner.path_set()
    assert trav.tolist() == [3]

    def force(qq: np.ndarray, v: np.ndarray, f_lambda: np.ndarray, lam: float) -> np.ndarray:
        return traveling_forces(qq, v, f_lambda, s.planner, np.full(4, lam), s.params)[3]

    return s, q, paths, force


# -- rho and Lambda: the secondaries' throttling -----------------------------------------------


@effect("multi_target:sigma")
def test_sigma_shapes_rho_and_a_larger_one_makes_an_opposed_secondary_yield() -> None:
    for sigma, opposed, aligned in ((1.0, 0.5, 0.5), (3.0, 0.125, 0.875)):
        s, q, _, force = travel_law(sigma=sigma)
        v, none = np.zeros((4, 3)), np.zeros((4, 3))
        full = force(q, v, none, 1.0)  # Lambda_hat = 1: rho = 1
        f_lambda = np.zeros((4, 3))
        for sign, want in ((-1.0, opposed), (1.0, aligned)):  # Theta = 0, then 1
            f_lambda[3] = sign * full
            got = force(q, v, f_lambda, 0.5)
            np.testing.assert_allclose(got, want * full, rtol=1e-12)  # eqs. (14)-(15)
    prime = {sg: tug(sigma=sg) for sg in (1.0, 3.0, 6.0)}
    assert prime[1.0][1] > prime[3.0][1] > prime[6.0][1]  # dragged back more and more
    assert prime[1.0][0] < prime[3.0][0] < prime[6.0][0]  # the prime gets farther


@effect("multi_target:xc_frac", "multi_target:xm_frac")
def test_a_wider_efficiency_band_rates_the_prime_higher_and_its_secondaries_yield_less() -> None:
    """``Lambda`` of eq. (9) is 1 up to ``xc_frac v_cruise``, 0 from ``xm_frac v_cruise``."""
    default = tug()
    for params in ({"xc_frac": 0.3}, {"xm_frac": 1.2}):
        wider = tug(**params)
        assert np.nanmean(wider[2]) > np.nanmean(default[2]) + 0.05, params
    narrow = tug(xc_frac=0.01, xm_frac=0.02)
    wide = tug(xc_frac=0.5, xm_frac=0.9)
    assert np.nanmax(narrow[2]) < 0.05 and np.nanmin(wide[2][~np.isnan(wide[2])][1:]) > 0.9
    assert narrow[1] < default[1] < wide[1]  # the secondary: throttled most when rated lowest
    assert narrow[0] > default[0] > wide[0]


@effect("multi_target:k_lambda_per_s")
def test_a_slower_consensus_leaves_the_secondaries_throttled_longer() -> None:
    """Eq. (13): robot 3, three hops from the prime, learns its efficiency at k_Lambda."""
    s, q = started(two_travelers(k_lambda_per_s=1.0))
    links = s._links()
    for gain, after_one in ((1.0, 0.1), (2.0, 0.2), (5.0, 1 / 3)):  # step min(k h, 1/(deg+1))
        s, q = started(two_travelers(k_lambda_per_s=gain))
        s.consensus.round(links, 0.1, 0, 1.0)
        assert s.consensus.estimate[1] == pytest.approx(after_one)
    slow, fast = tug(k_lambda_per_s=0.2), tug()
    assert slow[1] < fast[1] and slow[0] > fast[0]


@effect("multi_target:alpha_lambda")
def test_alpha_weighs_the_prime_s_velocity_error_against_its_position_error() -> None:
    """Eq. (11): at its election the prime is at rest on its path (velocity error
    ``v_cruise`` = 3 m/s, position error 0): ``e = (1 - alpha) 3``, and eq. (9) with
    the band (0.3, 1.8) m/s gives 0 at alpha = 0, 1 at alpha = 0.9, between at 0.5."""
    first = []
    for alpha in (0.0, 0.5, 0.9):
        eff = columns(run(pulled("multi_target", alpha_lambda=alpha), 12))["prime_efficiency"]
        first.append(float(eff[~np.isnan(eff)][0]))
    band = 0.5 + 0.5 * np.cos((1.5 - 0.3) / (1.8 - 0.3) * np.pi)
    assert first == pytest.approx([0.0, band, 1.0], abs=0.02)
    # the other way round: 1 m off its path at the path's velocity, e = alpha 1 m
    for alpha in (0.2, 0.5, 0.9):
        s, q = started(scenario("multi_target", alpha_lambda=alpha))
        s.planner.set_role(3, PRIME, 0.0)
        off = q.copy()
        off[3, 1] += 1.0
        v = np.zeros_like(q)
        v[3] = s.planner.path_set()[1].states(off[[3]], 3.0).velocity_mps[0]
        s._communicate(off, v, 0.0, 0.1)
        want = 1.0 if alpha <= 0.3 else 0.5 + 0.5 * np.cos((alpha - 0.3) / 1.5 * np.pi)
        assert s._prime_eff == pytest.approx(want, abs=1e-9), alpha


# -- eq. (3): the traveling force --------------------------------------------------------------


@effect("multi_target:kp_n_per_m", "multi_target:kv_ns_per_m", "multi_target:max_travel_force_n")
def test_eq_3_pulls_back_to_the_path_and_matches_the_path_s_speed() -> None:
    """``M a_gamma + B v_gamma + kv (v_gamma - qdot) + kp (q_gamma - q)``, saturated: a
    robot 0.5 m off its path is pulled back by ``kp`` 0.5 m; one at twice the path's speed
    is braked by ``kv`` v_gamma (v_cruise 1 m/s keeps the sums below 10 N)."""
    for kp, kv in ((4.0, 4.0), (8.0, 4.0), (4.0, 8.0)):
        s, q, paths, force = travel_law(v_cruise_mps=1.0, kp_n_per_m=kp, kv_ns_per_m=kv)
        off = q.copy()
        off[3, 1] += 0.5
        st = paths.states(off[[3]], 1.0)
        v = np.zeros((4, 3))
        v[3] = 2.0 * st.velocity_mps[0]
        want = (st.acceleration_mps2[0] + 2.0 * st.velocity_mps[0] - kv * st.velocity_mps[0]
                + kp * (st.point_m[0] - off[3]))  # fmt: skip
        assert np.linalg.norm(want) < 10.0
        np.testing.assert_allclose(force(off, v, np.zeros((4, 3)), 1.0), want, atol=1e-9)
        assert np.linalg.norm(st.point_m[0] - off[3]) == pytest.approx(0.5, abs=1e-6)
    s, q, paths, force = travel_law(max_travel_force_n=2.0)  # from rest at 3 m/s: 18 N
    assert np.linalg.norm(force(q, np.zeros((4, 3)), np.zeros((4, 3)), 1.0)) == pytest.approx(2.0)
    weak = moved_m(run(pulled("multi_target", max_travel_force_n=2.0), 40))[3]
    assert weak < 0.6 * moved_m(run(pulled("multi_target"), 40))[3]


@effect("multi_target:v_cruise_mps")
def test_the_prime_cruises_at_v_cruise() -> None:
    for cruise in (1.0, 2.0):
        top = run(pulled("multi_target", v_cruise_mps=cruise), 80).metrics["max_speed_mps"]
        assert top == pytest.approx(cruise, rel=0.1)


# -- anchors: eqs. (5)-(7) and the ball of radius Rz -------------------------------------------


def anchored(**params: Any) -> dict[str, Any]:
    """Robot 0 anchors at its start for 60 s while robot 3, prime, drags the row away."""
    data = scenario("multi_target", **params)
    data["strategy"]["params"]["targets"]["params"]["queues"] = [
        {"robot": 0, "targets": [[0.0, 0.0, 5.0]], "stay_s": 60.0},
        {"robot": 3, "targets": [FAR_TARGET], "stay_s": 1.0},
    ]
    return data


@effect("multi_target:kz_n", "multi_target:max_anchor_force_n", "multi_target:rz_m")
def test_the_anchor_force_of_eq_7_and_its_bound() -> None:
    """``kz tan(l pi / (2 Rz))`` towards the target: kz at l = Rz / 2; near the rim the
    bound (10 N) saturates it; ``null`` is the paper's law, undefined from ``Rz`` on."""
    s, q, _, _ = travel_law()
    target = q[[0]] + [[0.0, 0.0, 0.0]]

    def pull(rz: float, l_frac: float, **params: Any) -> np.ndarray:
        s, q, _, _ = travel_law(rz_m=rz, **params)
        qq = q.copy()
        qq[0, 0] += l_frac * rz
        f = traveling_forces(qq, np.zeros((4, 3)), np.zeros((4, 3)), s.planner, np.zeros(4),
                             s.params, anchors=(np.array([0]), target))  # fmt: skip
        return f[0]

    for kz in (1.0, 3.0):
        np.testing.assert_allclose(pull(1.8, 0.5, kz_n=kz), [-kz, 0, 0], atol=1e-9)
    np.testing.assert_allclose(pull(1.0, 0.5, kz_n=3.0), [-3.0, 0, 0], atol=1e-9)
    rim = 1.0 * np.tan(0.99 * np.pi / 2)  # 63.7 N
    np.testing.assert_allclose(pull(1.8, 0.99), [-10.0, 0, 0], atol=1e-9)
    np.testing.assert_allclose(pull(1.8, 0.99, max_anchor_force_n=None), [-rim, 0, 0], rtol=1e-9)
    np.testing.assert_allclose(pull(1.8, 1.2, max_anchor_force_n=4.0), [-4.0, 0, 0], atol=1e-9)
    assert np.isnan(pull(1.8, 1.2, max_anchor_force_n=None)).all()


@effect("multi_target:max_anchor_force_n", "multi_target:guard")
def test_a_bounded_anchor_is_dragged_out_of_its_ball_unless_unbounded_or_enforced() -> None:
    out = {}
    for params in ({"max_anchor_force_n": 0.5}, {"max_anchor_force_n": None},
                   {"max_anchor_force_n": 0.5, "guard": "enforce"}):  # fmt: skip
        m = run(anchored(**params), 60).metrics
        out[len(params), params["max_anchor_force_n"]] = m
    assert out[1, 0.5]["anchor_outside_steps"] > 0 and out[1, 0.5]["guard_interventions"] == 0
    assert out[1, None]["anchor_outside_steps"] == 0
    enforced = out[2, 0.5]
    assert enforced["anchor_outside_steps"] == 0 and enforced["guard_interventions"] > 0


@effect("multi_target:rz_m")
def test_a_larger_anchoring_radius_ends_the_trip_sooner_and_farther_from_the_target() -> None:
    """Robot 3, prime, with its target 8 m ahead: on entering the ball of radius Rz it has
    arrived (line 14 of Algorithm 1: it hosts the next election)."""
    when = {}
    for rz in (1.0, 3.0):
        data = scenario("multi_target", rz_m=rz)
        data["strategy"]["params"]["targets"]["params"]["queues"][0]["targets"] = [[17, 0, 5]]
        r = run(data, 60)
        step = next(e["step"] for e in r.recorder.events
                    if e["kind"] == "election_open" and e["robot"] == 3)  # fmt: skip
        gap = float(np.linalg.norm(r.positions[step, 3] - [17, 0, 5]))
        assert rz - 0.5 < gap < rz, (rz, gap)
        when[rz] = step
    assert when[3.0] < when[1.0]


# -- eq. (16) -------------------------------------------------------------------------------


@effect("multi_target:reference_filter")
def test_the_reference_filter_records_a_smooth_reference_that_trails_the_robot() -> None:
    plain = run(pulled("multi_target"), 30)
    filtered = run(pulled("multi_target", reference_filter=True), 30)
    assert "reference_filter_max_deviation_m" not in plain.metrics
    assert "x_ref_m" not in plain.recorder.robot_columns()
    np.testing.assert_array_equal(filtered.positions, plain.positions)  # it only records
    lag = filtered.metrics["reference_filter_max_deviation_m"]
    assert 0.1 < lag < 2.0
    cols = filtered.recorder.robot_columns()
    ref_x = np.asarray(cols["x_ref_m"]).reshape(-1, 4)[-1]
    assert ref_x[3] < filtered.positions[-1, 3, 0]  # behind the prime, which moves along +x
