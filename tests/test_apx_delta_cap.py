"""APX's ``delta`` under ``MAX_TABLE_SUBSETS``: a large ``delta`` runs as the largest that fits.

Without the cap, ``delta = 30`` in ``recurrent_grass`` died after 22 s asking for 34 GiB
for one rank table. The cap lowers ``delta`` for a plan while the rank tables of the
sizes below it would index more than ``MAX_TABLE_SUBSETS`` subsets; the plan is then
exactly APX with the lowered ``delta``, and its upper bound (Theorem 4.1) stays a bound
on the optimum.
"""

from __future__ import annotations

import itertools
from math import comb

import pytest

from tether.recurrent.planning import apx
from tether.recurrent.planning import problem as _problem
from tether.recurrent.planning.apx import apx_delta, solve_apx
from tether.recurrent.planning.ilp import solve_ilp
from tether.recurrent.planning.synthetic import exploration_instance


def test_apx_delta_is_the_largest_that_fits() -> None:
    """Over a grid of frontier counts, budgets and deltas: within the three limits, within
    the cap (or 1), maximal, and flagged exactly when the cap (not a limit) lowered it."""
    for k, budget, delta in itertools.product(range(1, 130, 7), range(1, 14, 3), (1, 4, 9, 30)):
        used, capped = apx_delta(k, budget, delta)
        plain = min(delta, budget, k)
        assert 1 <= used <= plain
        tables = sum(comb(k, s) for s in range(2, used))
        assert used == 1 or tables <= apx.MAX_TABLE_SUBSETS
        assert used == plain or tables + comb(k, used) > apx.MAX_TABLE_SUBSETS
        assert capped == (used < plain)
    assert apx_delta(84, 12, 30) == (6, True)  # recurrent_grass's plan that died
    assert apx_delta(580, 12, 4) == (4, False)  # the paper's delta, far more frontiers


@pytest.mark.parametrize("seed", range(4))
def test_a_capped_plan_is_apx_with_the_lowered_delta(
    seed: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """With a tiny cap, delta = 30 runs as the largest delta that fits: the same result as
    asking for that delta, flagged, and its upper bound still above the ILP optimum."""
    inst = exploration_instance(seed, n_frontiers=30, n_busy=0)
    prob = _problem.build(inst.graph, inst.base, inst.utilities, 6, [])
    k = int((prob.dist[0, prob.frontiers] <= 6).sum())
    monkeypatch.setattr(apx, "MAX_TABLE_SUBSETS", comb(k, 2))  # room for the 2-subsets only
    capped = solve_apx(prob, 30)
    assert (capped.delta_used, capped.delta_capped) == (3, True)
    plain = solve_apx(prob, 3)
    assert not plain.delta_capped
    assert (capped.vertices, capped.utility, capped.upper_bound) == (
        plain.vertices,
        plain.utility,
        plain.upper_bound,
    )
    optimum = solve_ilp(prob, backend="highs").utility
    assert capped.utility <= optimum + 1e-9 <= capped.upper_bound + 2e-9
    if capped.proven_optimal:
        assert capped.utility == pytest.approx(optimum, abs=1e-9)


def test_a_run_with_a_large_delta_counts_its_capped_plans(
    tmp_path, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A run reports the plans whose delta the cap lowered: in the summary and in each
    such plan's event (with the delta used); the plans still satisfy the constraints."""
    import pyarrow.parquet as pq

    from tether.config import load_scenario
    from tether.runner import run as run_scenario

    monkeypatch.setattr(apx, "MAX_TABLE_SUBSETS", 30)  # a few frontiers fill it
    sc = load_scenario("recurrent_demo")
    sc.sim.max_steps = 40
    sc.output.figures = False
    sc.strategy.params["delta"] = 30
    out = run_scenario(sc, out_dir=tmp_path / "r")
    assert out.summary["plans_apx_delta_capped"] > 0
    assert out.summary["constraint_violations"] == 0
    events = pq.read_table(tmp_path / "r" / "events.parquet").to_pylist()
    capped = [e for e in events if e.get("apx_delta_capped")]
    assert len(capped) == out.summary["plans_apx_delta_capped"]
    assert all(1 <= e["apx_delta"] < 30 for e in capped)
