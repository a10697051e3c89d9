"""Robot failures: fail-stop in the simulator, recovery by the BS planner (Sec. VII-B)."""

from __future__ import annotations

import numpy as np
import pytest

from _exploration_helpers import office
from tether.recurrent.baseline_utility import UtilityStrategy
from tether.recurrent.exploration.sim import (
    ExplorationConfig,
    ExplorationSim,
    GoalKind,
    random_base,
)
from tether.recurrent.replanning import RecurrentStrategy
from tether.recurrent.strategy import FailureParams, failure_schedule


def make(policy, seed: int, n: int = 4, failures: dict | None = None) -> ExplorationSim:
    occ = office(seed, (12.0, 20.0))
    cfg = ExplorationConfig(n_robots=n, failures=failures or {})
    sim = ExplorationSim(occ, random_base(occ, 3, np.random.default_rng(seed)), policy, cfg)
    policy.start(sim)
    return sim


def spy(sim: ExplorationSim) -> list[tuple[int, int]]:
    """(step, robot) of every goal given (the stop of a failing robot itself excluded)."""
    log: list[tuple[int, int]] = []
    real = sim.assign

    def assign(robot, goal, kind, path, delay=0):
        if sim.alive[robot]:
            log.append((sim.t, int(robot)))
        real(robot, goal, kind, path, delay)

    sim.assign = assign
    return log


@pytest.mark.parametrize("seed", [0, 2, 7])
def test_relay_failure_triggers_recovery_and_the_mission_goes_on(seed: int) -> None:
    strat = RecurrentStrategy(theta=1, check=True)
    sim = make(strat, seed)
    victim = None
    for _ in range(60):  # until a robot relays for another one's P_f
        sim.step()
        keys = strat.goal_keys(sim)
        for o in strat.tracker.obligations:
            held = [r for r in range(sim.n) if int(keys[r]) in o.members - {o.target}]
            if held:
                victim = held[0]
                break
        if victim is not None:
            break
    assert victim is not None, "no relay to fail"
    branch = strat.tracker.branch(victim, strat.goal_keys(sim)) - {victim}
    assert branch, "the relay is bound with nobody"
    explored_at_failure = sim.explored_fraction()
    t_fail = sim.t + 1
    sim.cfg.failures = {victim: t_fail}
    log = spy(sim)
    where = sim.pos[victim].copy()
    reconnected = {r: False for r in branch}
    stranded = np.zeros(sim.n, dtype=int)  # steps standing still with no link to the BS
    for _ in range(120):
        sim.step()
        still = sim.alive & ~sim.connected & ~sim.moved
        stranded = np.where(still, stranded + 1, 0)
        assert not sim.alive[victim] and not sim.connected[victim]
        assert np.array_equal(sim.pos[victim], where)  # it stopped for good
        assert not np.isin(sim.links, victim + 1).any()  # and has no link (BS is node 0)
        for r in branch:
            reconnected[r] |= bool(sim.connected[r])
    recovery = [e for e in sim.events if e["kind"] == "recovery"]
    assert len(recovery) == 1 and recovery[0]["robot"] == victim
    assert set(recovery[0]["preempted"]) == branch
    assert strat.violations == []  # constraints (I)-(IV) on every plan after it
    assert all(r != victim for t, r in log if t >= t_fail)  # never planned for again
    assert any(p["issued"] and p["step"] > t_fail for p in strat.plans)
    assert sim.explored_fraction() > explored_at_failure
    assert all(reconnected.values())  # cut-off robots found their way back to the BS
    assert stranded.max() < 40  # and nobody stands cut off for good
    m = strat.metrics()
    assert m["robots_preempted_by_failures"] == len(branch) and m["plans_after_failures"] > 0


def test_theta_counts_only_live_robots() -> None:
    """theta = team size: after a failure the BS must not wait for a dead robot."""
    strat = RecurrentStrategy(theta=4, check=True)
    sim = make(strat, 3, n=4, failures={2: 5})
    for _ in range(80):
        sim.step()
    assert any(p["issued"] and p["step"] > 5 for p in strat.plans)
    assert strat.violations == []


def test_utility_leaves_failed_robots_alone() -> None:
    pol = UtilityStrategy()
    sim = make(pol, 1, n=4, failures={0: 3})
    log = spy(sim)
    for _ in range(60):
        sim.step()
    assert not sim.alive[0] and sim.goal_kind[0] == GoalKind.NONE
    assert all(r != 0 for t, r in log if t >= 3)
    assert {r for _, r in log} >= {1, 2, 3}


def test_failure_schedule() -> None:
    rng = np.random.default_rng(0)
    sched = failure_schedule(
        FailureParams(at_s={3: 100.0}, random=2, window_s=(50.0, 60.0)), 6, 900, 2.0, rng
    )
    assert sched[3] == 50 and len(sched) == 3
    assert all(25 <= t <= 30 for r, t in sched.items() if r != 3)
    again = failure_schedule(
        FailureParams(at_s={3: 100.0}, random=2, window_s=(50.0, 60.0)),
        6,
        900,
        2.0,
        np.random.default_rng(0),
    )
    assert again == sched  # a function of the seed
    assert failure_schedule(FailureParams(random=4), 4, 100, 1.0, rng).keys() == {0, 1, 2, 3}
    with pytest.raises(ValueError, match="9 robots cannot fail at random in a team of 4"):
        failure_schedule(FailureParams(random=9), 4, 100, 1.0, rng)  # refused, not capped
    with pytest.raises(ValueError, match="no robot 7"):
        failure_schedule(FailureParams(at_s={7: 1.0}), 4, 100, 1.0, rng)


@pytest.mark.parametrize("seed", [3, 5])
def test_robots_cut_off_by_a_failure_are_recovered_too(seed: int) -> None:
    """A robot linked to the BS only through the failed one, though bound with it by no ``P_f``."""
    from tether.graph import components

    strat = RecurrentStrategy(theta=1, check=True)
    sim = make(strat, seed, n=5)
    victim = None
    for _ in range(80):
        sim.step()
        keys = strat.goal_keys(sim)
        for a in range(sim.n):
            pairs = sim.links[~np.isin(sim.links, a + 1).any(axis=1)]
            _, lab = components(sim.n + 1, pairs)
            branch = strat.tracker.branch(a, keys)
            if any(sim.connected[b] and lab[b + 1] != lab[0] and sim.at_goal[b]
                   and b not in branch for b in range(sim.n)):  # fmt: skip
                victim = a
                break
        if victim is not None:
            break
    assert victim is not None
    before = sim.connected.copy()
    sim.cfg.failures = {victim: sim.t + 1}
    sim.step()
    lost = set(np.flatnonzero(before & ~sim.connected & sim.at_goal & sim.alive).tolist())
    recovery = [e for e in sim.events if e["kind"] == "recovery"][-1]
    assert lost <= set(recovery["preempted"])
    back = {r: False for r in lost}
    for _ in range(80):
        sim.step()
        for r in lost:
            back[r] |= bool(sim.connected[r])
    assert all(back.values()) and strat.violations == []
