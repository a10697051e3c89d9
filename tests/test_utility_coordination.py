"""Utility baseline ``coordination``: with ``none`` two robots may pick one frontier.

With ``greedy`` (joint assignment inside a communicating group) they never do.
"""

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


def corridor() -> np.ndarray:
    """A straight corridor 10 cells wide and 250 long: one frontier ahead of the team."""
    occ = np.ones((260, 30), dtype=bool)
    occ[2:252, 10:20] = False
    return occ


def start(coordination: str, n: int = 3) -> ExplorationSim:
    pol = UtilityStrategy(coordination=coordination)
    sim = ExplorationSim(corridor(), np.array([6.0, 15.0]), pol, ExplorationConfig(n_robots=n))
    pol.start(sim)
    return sim


def test_none_sends_every_robot_to_the_one_frontier() -> None:
    sim = start("none")
    assert len(sim.groups) == 1  # they all talk
    assert (sim.goal_kind == GoalKind.FRONTIER).all()
    assert np.allclose(sim.goal, sim.goal[0])


def test_greedy_gives_the_one_frontier_to_one_robot() -> None:
    sim = start("greedy")
    frontier = np.flatnonzero(sim.goal_kind == GoalKind.FRONTIER)
    assert len(frontier) == 1
    assert sim.strategy.exhausted.sum() == sim.n - 1


def test_unknown_coordination_is_refused() -> None:
    with pytest.raises(ValueError, match="coordination"):
        start("auction")


def _spy_assignments(sim: ExplorationSim) -> list[tuple[int, int, tuple[float, float]]]:
    log: list[tuple[int, int, tuple[float, float]]] = []
    real = sim.assign

    def assign(robot, goal, kind, path, delay=0):
        if kind == GoalKind.FRONTIER:
            log.append((sim.t, int(robot), tuple(np.round(goal, 6))))
        real(robot, goal, kind, path, delay)

    sim.assign = assign
    return log


@pytest.mark.parametrize(("coordination", "seed"), [("greedy", 0), ("greedy", 3), ("none", 0)])
def test_no_two_robots_of_a_group_choose_one_frontier_with_greedy(
    coordination: str, seed: int
) -> None:
    occ = office(seed, (12.0, 20.0))
    pol = UtilityStrategy(coordination=coordination)
    cfg = ExplorationConfig(n_robots=4, steps=100)
    sim = ExplorationSim(occ, random_base(occ, 3, np.random.default_rng(seed)), pol, cfg)
    log = _spy_assignments(sim)
    shared = 0
    pol.start(sim)
    for _ in range(cfg.steps):
        before = len(log)
        goals_before = {
            r: tuple(np.round(sim.goal[r], 6))
            for r in range(sim.n)
            if sim.goal_kind[r] == GoalKind.FRONTIER
        }
        sim.step()
        chosen = log[before:]
        group_of = {r: k for k, g in enumerate(sim.groups) for r in g}
        for i, (_, r, goal) in enumerate(chosen):
            mates = {m for m in sim.groups[group_of[r]] if m != r}
            same_now = [s for _, s, g in chosen[i + 1 :] if s in mates and g == goal]
            # a teammate that keeps heading to this frontier
            kept = [m for m in mates if goals_before.get(m) == goal and m not in
                    {s for _, s, _ in chosen}]  # fmt: skip
            shared += len(same_now) + len(kept)
    assert log, "no frontier was chosen"
    if coordination == "greedy":
        assert shared == 0
    else:
        assert shared > 0  # robots that talk do pick one frontier together
