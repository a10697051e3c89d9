"""``guard: detect | enforce | off`` on both eigensolvers.

The decentralized estimator with one message round per sub-step cannot keep up with the
office team's motion (``connectivity_office``): left alone, its force lets lambda2 reach 0
within a second. ``detect`` must let that happen and count it, ``enforce`` must prevent it
and count every intervention, ``off`` must change nothing of the motion and measure
nothing, and none of them may call a run with an exit or an intervention a success.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from tether.config import load_scenario
from tether.continuous.connectivity.strategy import ConnectivityStrategy, ConnectivityStrategyParams
from tether.continuous.connectivity.weights import WeightedGraph
from tether.errors import ScenarioError
from tether.record import TrajectoryRecorder
from tether.runner import build
from tether.sim import StepContext, TeamState, simulate
from tether.world.scenes import make_scene


def run(guard: str, steps: int, eigensolver: str = "estimator") -> tuple[dict, np.ndarray, dict]:
    sc = load_scenario("connectivity_office")
    sc.strategy.params.update(guard=guard, eigensolver=eigensolver)
    sc.strategy.params["estimator"].update(rounds_per_substep=1, warmup_rounds=10)
    b = build(sc)
    rec = TrajectoryRecorder(every=1)
    res = simulate(b.world, b.sensor, b.strategy, b.initial, dt_s=0.1, max_steps=steps,
                   rng=b.rng, recorder=rec)  # fmt: skip
    return res.strategy_metrics, res.final_state.positions, rec.step_columns()


def test_detect_lets_the_controller_fail_and_counts_every_sub_step_outside() -> None:
    m, _, cols = run("detect", 20)
    assert m["min_lambda2_weighted"] == 0.0 and m["safe_set_exits"] > 0
    assert m["guard_interventions"] == 0 and m["controller_success"] is False
    total = np.asarray(cols["safe_set_exits_total"])
    assert total[0] == 0 and total[-1] == m["safe_set_exits"] and np.all(np.diff(total) >= 0)


def test_enforce_holds_the_invariant_and_is_never_a_success_when_it_acted() -> None:
    m, _, _ = run("enforce", 12)
    assert m["min_lambda2_weighted"] > 0.0 and m["safe_set_exits"] == 0
    assert m["guard_interventions"] > 0 and m["controller_success"] is False


@pytest.mark.parametrize("eigensolver", ["estimator", "exact"])
def test_off_moves_the_team_as_detect_does_and_measures_nothing(
    eigensolver: str, monkeypatch
) -> None:
    m_detect, q_detect, _ = run("detect", 10, eigensolver)
    calls = {"n": 0}
    fiedler = WeightedGraph.fiedler

    def counting(self, *a, **kw):  # noqa: ANN001, ANN002, ANN003, ANN202
        calls["n"] += 1
        return fiedler(self, *a, **kw)

    monkeypatch.setattr(WeightedGraph, "fiedler", counting)
    m_off, q_off, _ = run("off", 10, eigensolver)
    np.testing.assert_array_equal(q_off, q_detect)
    assert m_off["controller_success"] is None and m_off["safe_set_exits"] == 0
    if eigensolver == "estimator":  # only the per-step record, never a sub-step check
        assert calls["n"] <= 1 + 10 + 1
        assert m_detect["substeps"] > 10 + 2


def test_the_old_safeguard_key_says_what_replaced_it() -> None:
    sc = load_scenario("connectivity_office")
    sc.strategy.params["safeguard"] = True
    with pytest.raises(ScenarioError, match="guard: detect"):
        build(sc)


def test_the_sweep_report_counts_the_controller_s_successes_per_combination(tmp_path) -> None:
    """Exact lambda2 keeps the office team in its safe set; one estimator round per
    sub-step does not: the report must tell the two combinations apart."""
    from tether.experiments.report import write_report
    from tether.experiments.sweep import run_sweep

    sc = load_scenario("connectivity_office")
    sc.sim.max_steps = 20
    sc.strategy.params["estimator"].update(rounds_per_substep=1, warmup_rounds=10)
    sc.sweep = {"strategy.params.eigensolver": ["exact", "estimator"]}
    run_sweep(sc, tmp_path / "sweep", seeds=1)
    text = write_report(tmp_path / "sweep").read_text()
    table = text[text.index("## Controller success") : text.index("## Figures")]
    rows = {line.split("|")[1].strip(): [c.strip() for c in line.split("|")[2:-1]]
            for line in table.splitlines() if "eigensolver" in line}  # fmt: skip
    exact = next(v for k, v in rows.items() if "exact" in k)
    estimator = next(v for k, v in rows.items() if "estimator" in k)
    assert exact[:4] == ["1", "1", "0", "0"] and estimator[:4] == ["1", "0", "1", "0"]
    assert estimator[4] == "1"  # the trial with safe-set exits


def test_a_run_whose_step_rule_gave_up_is_not_a_success() -> None:
    """A stretched chain near the barrier needs rejected sub-steps; with no retry allowed
    the step rule gives up (``tolerance_misses``), and the run is no success even though
    the guard never acted and the team never left the safe set."""
    q = np.zeros((6, 3))
    q[:, 0], q[:, 2] = np.arange(6) * 5.5, 20.0  # links near Rs: lambda2 near the barrier
    outcomes = {}
    for retries in (30, 0):
        world, rng = make_scene("free", 0, dim=3), np.random.default_rng(0)
        strategy = ConnectivityStrategy(ConnectivityStrategyParams(preset="outdoor"))
        strategy.reset(world, TeamState.at_rest(q), rng)
        strategy.integ = dataclasses.replace(strategy.integ, max_retries=retries)
        state = TeamState.at_rest(q)
        for k in range(10):
            state = strategy.step(StepContext(k, k * 0.1, 0.1, world, state, None, rng))
        outcomes[retries] = strategy.metrics()
    assert outcomes[30]["tolerance_misses"] == 0 and outcomes[30]["controller_success"] is True
    m = outcomes[0]
    assert m["tolerance_misses"] > 0 and m["guard_interventions"] == m["safe_set_exits"] == 0
    assert m["controller_success"] is False
