"""``explored_fraction``, counted once per version of the BS map, equals counting it.

Each step of a few runs of the planner (robots move, links break and form, the BS map
grows or not) is checked against the count from scratch.
"""

from __future__ import annotations

import numpy as np

from _exploration_helpers import office
from tether.recurrent.exploration.sim import ExplorationConfig, ExplorationSim, random_base
from tether.recurrent.replanning import RecurrentStrategy


def _check_run(seed: int) -> tuple[int, int]:
    """Steps of one run, steps the BS map grew in."""
    occ = office(seed, (12.0, 20.0))
    cfg = ExplorationConfig(n_robots=6, steps=100, link_params={"range_cells": 40.0})
    strategy = RecurrentStrategy(theta=1)
    sim = ExplorationSim(occ, random_base(occ, 3, np.random.default_rng(seed)), strategy, cfg)
    strategy.start(sim)
    grown = 0
    for _ in range(cfg.steps):
        version = sim.knowledge.global_version
        sim.explored_fraction()  # counted for the map before the step
        sim.step()
        free = sim.knowledge.global_known & sim.free_region
        assert sim.explored_fraction() == np.count_nonzero(free) / sim.free_total
        grown += sim.knowledge.global_version != version
    return cfg.steps, grown


def test_kept_share_equals_the_count() -> None:
    steps, grown = np.sum([_check_run(seed) for seed in range(1, 5)], axis=0)
    assert 0 < grown < steps  # both ways ran: kept and recounted
