"""What the exploration simulator keeps from one step to the next equals recomputing it.

``explored_fraction`` is counted once per version of the BS map, and the components
of the communication graph are reused while the link pairs stay the same. Each step
of a few runs of the planner (robots move, links break and form, the BS map grows) is
checked against the values computed from scratch.
"""

from __future__ import annotations

import numpy as np

from _exploration_helpers import office
from tether.graph import components
from tether.recurrent.exploration.sim import ExplorationConfig, ExplorationSim, random_base
from tether.recurrent.replanning import RecurrentStrategy


def _check_run(seed: int) -> tuple[int, int, int]:
    """Steps of one run, steps that reused the components, steps the BS map grew in."""
    occ = office(seed, (12.0, 20.0))
    cfg = ExplorationConfig(n_robots=6, steps=100, link_params={"range_cells": 40.0})
    strategy = RecurrentStrategy(theta=1)
    sim = ExplorationSim(occ, random_base(occ, 3, np.random.default_rng(seed)), strategy, cfg)
    strategy.start(sim)
    reused = grown = 0
    for _ in range(cfg.steps):
        version, pairs = sim.knowledge.global_version, sim._components
        sim.explored_fraction()  # counted for the map before the step
        sim.step()
        free = sim.knowledge.global_known & sim.free_region
        assert sim.explored_fraction() == np.count_nonzero(free) / sim.free_total
        _, lab = components(sim.n + 1, sim.links)
        assert np.array_equal(sim.connected, lab[1:] == lab[0])
        keys = sorted(set(lab[1:].tolist()))
        assert sim.groups == [np.flatnonzero(lab[1:] == k).tolist() for k in keys]
        reused += sim._components is pairs
        grown += sim.knowledge.global_version != version
    return cfg.steps, reused, grown


def test_kept_values_equal_recomputed_ones() -> None:
    steps, reused, grown = np.sum([_check_run(seed) for seed in range(1, 5)], axis=0)
    assert 0 < reused < steps and 0 < grown < steps  # both ways ran: kept and recomputed
