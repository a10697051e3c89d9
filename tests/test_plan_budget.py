"""Bounded planning: the exact method within a time budget, APX as fallback.

The synthetic instance (seed 11, 200 vertices, 2,000 edges) is the hardest of seeds
0-29 for the HiGHS ILP: not proven optimal within 60 s (44 s CPU; seed 0, used here
before, is now proven in about 1.5 s); with a budget the call returns in about the
budget with the best configuration found, never worse than APX.
"""

from __future__ import annotations

import time

import numpy as np
import pytest

from _exploration_helpers import office
from tether.recurrent.exploration.sim import ExplorationConfig, ExplorationSim, random_base
from tether.recurrent.planning.configuration import check_configuration, optimal_configuration
from tether.recurrent.planning.synthetic import exploration_instance
from tether.recurrent.replanning import RecurrentStrategy

pytest.importorskip("highspy")


#: The budget is wall-clock time, so the test bounds the call's wall time, loosely:
#: a busy machine stretches the phase under way at the deadline (HiGHS honours its
#: limit between iterations; the reductions before the solver are checked between
#: phases), so the bound only catches a budget that is ignored (this instance needs
#: more than 40 s to be proven optimal), not a slow overrun.
def overrun_bound_s(budget: float) -> float:
    return 3.0 * budget + 2.0


@pytest.fixture(scope="module")
def hard():
    inst = exploration_instance(11)
    apx = optimal_configuration(inst.graph, inst.base, inst.utilities, inst.budget, "apx")
    return inst, apx


@pytest.mark.parametrize("budget", [1.0, 2.0])
def test_budget_is_respected_and_the_plan_is_valid(hard, budget: float) -> None:
    inst, apx = hard
    tic = time.perf_counter()
    conf = optimal_configuration(
        inst.graph, inst.base, inst.utilities, inst.budget, "ilp", backend="highs",
        time_limit_s=budget,
    )  # fmt: skip
    elapsed = time.perf_counter() - tic
    assert elapsed <= overrun_bound_s(budget)
    assert conf.solve_time_s <= elapsed + 1e-6
    assert conf.timed_out and not conf.proven_optimal  # flagged: best found, not proven
    assert conf.utility >= apx.utility - 1e-9  # never worse than the fallback
    assert conf.upper_bound >= conf.utility
    assert check_configuration(inst.graph, inst.base, conf.vertices, inst.utilities,
                               inst.budget) == []  # fmt: skip


def test_no_time_left_gives_the_apx_configuration(hard) -> None:
    inst, apx = hard
    conf = optimal_configuration(
        inst.graph, inst.base, inst.utilities, inst.budget, "ilp", backend="highs",
        time_limit_s=1e-6,
    )  # fmt: skip
    assert conf.fallback and conf.timed_out and not conf.proven_optimal
    assert conf.vertices == apx.vertices and conf.utility == pytest.approx(apx.utility)


def test_small_instances_are_still_proven_within_budget() -> None:
    inst = exploration_instance(3, n_vertices=40, n_edges=200, n_frontiers=6, n_robots=4,
                                explored_radius_m=12.0)  # fmt: skip
    conf = optimal_configuration(inst.graph, inst.base, inst.utilities, inst.budget, "ilp",
                                 backend="highs", time_limit_s=30.0)  # fmt: skip
    assert conf.proven_optimal and not conf.timed_out and not conf.fallback


def test_simulation_plans_within_budget() -> None:
    """A run whose every ILP plan has no time: APX plans, flagged, with no violation."""
    occ = office(5, (12.0, 20.0))
    strat = RecurrentStrategy(theta=3, method="ilp", check=True, time_limit_s=1e-6)
    cfg = ExplorationConfig(n_robots=3)
    sim = ExplorationSim(occ, random_base(occ, 3, np.random.default_rng(5)), strat, cfg)
    strat.start(sim)
    for _ in range(40):
        sim.step()
    issued = [p for p in strat.plans if p["issued"]]
    assert issued and all(p["timed_out"] and p["fallback"] for p in issued)
    assert all(not p["proven_optimal"] for p in issued)
    assert strat.violations == []
    assert strat.metrics()["plans_timed_out"] == len(issued)
