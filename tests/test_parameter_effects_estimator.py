"""The eigensolver and the decentralized estimator of Yang et al. (2010) in ``connectivity``
and ``multi_target`` (``docs/continuous.md``, "Decentralized estimation"; the gains in
:mod:`tether.continuous.connectivity.estimation`), each set from a scenario: the strategy ``build``
made is reset (its estimator warms up on the initial team) or run for a few periods."""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from _continuous_runs import STRATEGIES, both, moved_m, pulled, reset, run, scenario, started
from _parameters import effect
from tether.graph import small

BOTH = pytest.mark.parametrize("strategy", STRATEGIES)
GAINS = ("k1", "k2", "k3", "gamma", "kp", "ki", "step_scale")


def estimating(strategy: str, warmup: int, **estimator: Any):  # noqa: ANN201
    """The strategy reset with the estimator after ``warmup`` rounds on the initial row."""
    return reset(scenario(strategy, eigensolver="estimator",
                          estimator={"warmup_rounds": warmup, **estimator}))  # fmt: skip


def exact_lambda2(s) -> float:  # noqa: ANN001
    """The exact weighted lambda2 of the initial team (the strategy's own record of it)."""
    return float(s._min["lambda2"])


def estimates(strategy: str, warmup: int, **estimator: Any) -> tuple[np.ndarray, float]:
    """Every robot's lambda2 estimate after ``warmup`` rounds, and the exact lambda2."""
    s = estimating(strategy, warmup, **estimator)
    return s.estimator.lambda2.copy(), exact_lambda2(s)


def rel_error(strategy: str, warmup: int, **estimator: Any) -> float:
    est, lam = estimates(strategy, warmup, **estimator)
    return float(np.max(np.abs(est - lam)) / lam)


# -- which eigensolver -----------------------------------------------------------------------


@BOTH
@effect(*both("eigensolver"))
def test_the_estimator_lags_where_the_exact_eigenpair_keeps_the_safe_set(strategy: str) -> None:
    lagging = {"rounds_per_substep": 1, "warmup_rounds": 10}
    exact = run(pulled(strategy, estimator=lagging), 25).metrics
    est = run(pulled(strategy, eigensolver="estimator", estimator=lagging), 25).metrics
    assert exact["eigensolver"] == "exact" and est["eigensolver"] == "estimator"
    assert exact["safe_set_exits"] == 0 and "estimator_lambda2_rel_error_max" not in exact
    assert est["safe_set_exits"] > 0 and est["estimator_lambda2_rel_error_max"] > 0.1


@BOTH
@effect(*both("fiedler_method"))
def test_lapack_replaces_the_certified_small_solver_with_the_same_eigenpair(
    strategy: str, monkeypatch
) -> None:
    """From 17 robots on, ``auto`` solves with :func:`tether.graph.small.small_fiedler`
    warm-started from the previous vector; ``lapack`` never does; lambda2 is the same."""
    calls = {"n": 0}
    solver = small.small_fiedler

    def counting(*a, **kw):  # noqa: ANN002, ANN003, ANN202
        calls["n"] += 1
        return solver(*a, **kw)

    monkeypatch.setattr(small, "small_fiedler", counting)
    lam = {}
    for method in ("auto", "lapack"):
        data = scenario(strategy, fiedler_method=method)
        grid = [[3.0 * (k % 6), 3.0 * (k // 6)] + ([5.0] if strategy == "multi_target" else [])
                for k in range(17)]  # fmt: skip
        data["team"] = {"n_robots": 17, "init": {"kind": "positions", "positions": grid}}
        s = reset(data)
        calls["n"] = 0
        q = np.asarray(grid) + 0.1 * np.random.default_rng(0).normal(size=(17, len(grid[0])))
        lam[method] = s.evaluate(q)[0]
        assert (calls["n"] > 0) == (method == "auto"), method
    assert lam["lapack"] == pytest.approx(lam["auto"], rel=1e-12)


# -- rounds and the message layer ------------------------------------------------------------


@BOTH
@effect(*both("estimator.warmup_rounds"))
def test_warm_up_rounds_bring_the_estimate_to_lambda2_before_the_first_step(strategy: str) -> None:
    assert estimating(strategy, 40).estimator.rounds == 40
    assert rel_error(strategy, 40) > 0.5  # still near its start
    assert rel_error(strategy, 3000) < 1e-3


@BOTH
@effect(*both("estimator.rounds_per_substep"))
def test_more_rounds_per_sub_step_keep_the_estimate_up_with_the_motion(strategy: str) -> None:
    few = run(pulled(strategy, eigensolver="estimator",
                     estimator={"rounds_per_substep": 1, "warmup_rounds": 10}), 25)  # fmt: skip
    many = run(pulled(strategy, eigensolver="estimator",
                      estimator={"rounds_per_substep": 40, "warmup_rounds": 10}), 25)  # fmt: skip
    assert few.built.strategy.estimator.rounds == 10 + few.metrics["substeps"]
    assert many.built.strategy.estimator.rounds == 10 + 40 * many.metrics["substeps"]
    a, b = few.metrics, many.metrics
    assert b["estimator_lambda2_rel_error_mean"] < 0.5 * a["estimator_lambda2_rel_error_mean"]
    assert a["safe_set_exits"] > 0 and b["safe_set_exits"] == 0


@BOTH
@effect(*both("estimator.loss_probability"))
def test_each_message_is_lost_with_the_loss_probability(strategy: str) -> None:
    for p in (0.0, 0.3):
        s = estimating(strategy, 2000, loss_probability=p)
        assert s.estimator.comm.delivery_ratio == pytest.approx(1 - p, abs=0.02)
    lossy = run(pulled(strategy, eigensolver="estimator",
                       estimator={"loss_probability": 0.3, "warmup_rounds": 500}), 3)  # fmt: skip
    assert lossy.metrics["message_delivery_ratio"] == pytest.approx(0.7, abs=0.02)


@BOTH
@effect(*both("estimator.delay_rounds"))
def test_messages_arrive_delay_rounds_late(strategy: str) -> None:
    assert estimating(strategy, 5, delay_rounds=5).estimator.comm.delivered == 0
    assert estimating(strategy, 6, delay_rounds=5).estimator.comm.delivered > 0
    assert estimating(strategy, 1).estimator.comm.delivered > 0
    # without its neighbours' values for 5 rounds the estimate is not where it would be
    late, _ = estimates(strategy, 5, delay_rounds=5)
    fresh, _ = estimates(strategy, 5)
    assert np.abs(late - fresh).max() > 1e-3


@effect("multi_target:estimator.failures")
def test_a_failed_multi_target_robot_stops_and_exerts_no_force() -> None:
    """The traveler (robot 3) fails at round 0: it neither travels nor pulls anyone."""
    moved = {}
    for failures in ({}, {3: 0}):
        data = pulled("multi_target", eigensolver="estimator",
                      estimator={"failures": failures, "warmup_rounds": 300})  # fmt: skip
        moved[len(failures)] = moved_m(run(data, 40))
    assert moved[0][3] > 2.0 and moved[0][2] > 1.0  # the prime travels and drags the row
    assert moved[1][3] == 0.0 and moved[1].max() < 0.1


# -- the estimator's gains ---------------------------------------------------------------------


@BOTH
@effect(*both(*(f"estimator.{g}" for g in GAINS)))
def test_one_round_follows_the_estimator_ode_with_the_gains_given(strategy: str) -> None:
    """Yang et al.'s ODE, one Euler round from a random state, by hand::

    dx = -k1 y1 - k2 (L_W x) - k3 (y2 - 1) x,   dy = gamma (u - y) - kp L y + ki L w,
    dw = -ki L y  (u = x for y1, w1 and x^2 for y2, w2)

    with the step ``step_scale / (k1 + k3 + gamma + 2 k2 dW + 2 (kp + ki) d)``."""
    gains = {"k1": 5.0, "k2": 0.7, "k3": 1.5, "gamma": 3.0, "kp": 2.5, "ki": 1.1,
             "step_scale": 0.8}  # fmt: skip
    s, q = started(scenario(strategy, eigensolver="estimator",
                            estimator={"warmup_rounds": 0, **gains}))  # fmt: skip
    est = s.estimator
    assert est.params.model_dump() == gains
    graph = s.evaluate(q)[1][0]
    pairs, w = graph.active()
    n = est.n
    lap_w, lap = np.zeros((n, n)), np.zeros((n, n))
    for (i, j), wij in zip(pairs, w, strict=True):
        for m, val in ((lap_w, wij), (lap, 1.0)):
            m[i, j] -= val
            m[j, i] -= val
            m[i, i] += val
            m[j, j] += val
    state = np.random.default_rng(1).normal(size=(n, 5))
    est.state = state.copy()
    est.update(graph, 1)
    x, y1, w1, y2, w2 = state.T
    g = gains
    step = g["step_scale"] / (g["k1"] + g["k3"] + g["gamma"] + 2 * g["k2"] * np.diag(lap_w).max()
                              + 2 * (g["kp"] + g["ki"]) * np.diag(lap).max())  # fmt: skip
    want = state + step * np.column_stack([
        -g["k1"] * y1 - g["k2"] * lap_w @ x - g["k3"] * (y2 - 1) * x,
        g["gamma"] * (x - y1) - g["kp"] * lap @ y1 + g["ki"] * lap @ w1,
        -g["ki"] * lap @ y1,
        g["gamma"] * (x * x - y2) - g["kp"] * lap @ y2 + g["ki"] * lap @ w2,
        -g["ki"] * lap @ y2,
    ])  # fmt: skip
    np.testing.assert_allclose(est.state, want, rtol=1e-12, atol=1e-12)


@BOTH
@effect(*both("estimator.k2", "estimator.k3"))
def test_the_estimate_saturates_at_k3_over_k2(strategy: str) -> None:
    """The row's lambda2 (about 0.58 with no pull) is above ``k3 / k2`` = 0.2 and 0.1."""
    est, lam = estimates(strategy, 3000)
    assert est == pytest.approx(lam, rel=1e-3)  # k3 / k2 = 2: no saturation
    assert estimates(strategy, 1000, k3=0.2)[0] == pytest.approx(0.2, rel=1e-3)
    assert estimates(strategy, 1000, k3=0.2, k2=2.0)[0] == pytest.approx(0.1, rel=1e-3)


@effect(*both("estimator.k1", "estimator.step_scale"))
def test_a_larger_k1_or_a_smaller_step_scale_shortens_every_round() -> None:
    """Both shorten the Euler step (``step_scale / (k1 + ...)``): more rounds to converge."""
    for strategy in STRATEGIES:
        errors = [rel_error(strategy, 1000, k1=k1) for k1 in (2.5, 4.0, 40.0)]
        assert errors[0] < errors[1] < 0.05 < 1.0 < errors[2], errors
        assert rel_error(strategy, 1000, step_scale=0.2) > 1.0
        assert rel_error(strategy, 5000, step_scale=0.2) < 0.05


@effect("connectivity:estimator.gamma")
def test_gamma_one_swings_around_lambda2_where_the_default_settles() -> None:
    """Module docstring: the mean mode is nearly undamped for ``gamma = 1``."""
    lam = estimates("connectivity", 0)[1]
    swing = [float(np.median(estimates("connectivity", k, gamma=1.0)[0])) / lam
             for k in (1000, 3000)]  # fmt: skip
    assert swing[0] < 0.95 and swing[1] > 1.05, swing  # below, then above
    assert rel_error("connectivity", 3000) < 1e-3


@effect("connectivity:estimator.kp")
def test_a_larger_kp_shortens_every_round_and_slows_the_estimate() -> None:
    """``kp`` is in the step's divisor (``2 (kp + ki) d``); above the default that
    outweighs its faster proportional consensus."""
    errors = [rel_error("connectivity", 1000, kp=kp) for kp in (2.0, 8.0, 20.0)]
    assert errors[0] < 0.05 < errors[1] < errors[2], errors


@effect("connectivity:estimator.ki")
def test_the_integral_gain_carries_the_consensus_and_any_ki_converges() -> None:
    """A larger ``ki`` converges in fewer rounds; with ``ki`` 0.1 the estimate has not left
    its start after 3000 rounds; with ``ki`` 12 (the PI consensus oscillates fast) it
    still converges, never overflows."""
    errors = [rel_error("connectivity", 600, ki=ki) for ki in (1.0, 3.0, 6.0)]
    assert errors[0] > errors[1] > errors[2], errors
    assert rel_error("connectivity", 3000, ki=0.1) > 1.0
    est, lam = estimates("connectivity", 3000, ki=12.0)
    assert np.all(np.isfinite(est)) and est == pytest.approx(lam, rel=1e-2)
