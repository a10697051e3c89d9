"""Information latency on the real exploration simulator: a corridor, known reconnections.

One robot drives a straight corridor out of the base station's range and back, twice.
Its link to the base station (a disk of 13 cells) holds while it is within 13 cells,
so the reconnection schedule is known by hand, and every cell's latency must be the
delay from its first sighting to the next step the robot is linked.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from tether.recurrent.exploration.run import ExplorationRun
from tether.recurrent.exploration.sim import ExplorationConfig, ExplorationSim, GoalKind
from tether.sim import TeamState, simulate
from tether.world.grid import OccupancyGrid
from tether.world.world import World

BASE_X = 4.5  # the base station's coarse cell centre (cells)
LEGS = (40.5, BASE_X, 70.5, BASE_X + 1.0)  # out 36 cells, back, out 66, back (not onto
# its start, so the robot is not already at its goal)


class Shuttle:
    """Sends the robot along the corridor legs at the start, then does nothing."""

    name = "shuttle"

    def start(self, sim: ExplorationSim) -> None:
        path = np.array([[x, 4.5] for x in LEGS])
        sim.assign(0, path[-1], GoalKind.RELAY, path)

    def update(self, sim: ExplorationSim) -> None:
        pass

    def metrics(self) -> dict[str, Any]:
        return {}


def corridor_run() -> ExplorationRun:
    occupied = np.ones((80, 7), dtype=bool)
    occupied[1:79, 1:6] = False
    cfg = ExplorationConfig(
        n_robots=1, steps=110, speed_cells=2.0, sensor_range_cells=5.0,
        link_model="disk", link_params={"range_cells": 13.0},
    )  # fmt: skip
    grid = OccupancyGrid(occupied)
    run = ExplorationRun(Shuttle(), cfg, grid, np.array([BASE_X, 4.5]))
    simulate(
        World(dim=2, grid=grid), None, run,
        TeamState.at_rest(np.array([[BASE_X, 4.5]]), fixed=np.array([[BASE_X, 4.5]])),
        dt_s=1.0, max_steps=cfg.steps, rng=np.random.default_rng(0),
    )  # fmt: skip
    return run


def test_corridor_latency_follows_the_reconnection_schedule() -> None:
    run = corridor_run()
    log = run.log
    linked = np.array([bool(x[0]) for x in log.linked])
    # by hand: 2 cells per step; linked within 13 cells: steps 0..6 (out), 30..42
    # (back past 12 cells, out again until 12 cells), 96.. (back)
    want = np.zeros(len(linked), bool)
    want[:7] = want[30:43] = want[96:] = True
    assert (linked == want).all(), np.flatnonzero(linked != want)
    seen = log.robot_step[0]
    cells = np.flatnonzero((seen >= 0) & log.reachable)
    next_link = {s: int(np.flatnonzero(linked[s:])[0]) + s for s in np.unique(seen[cells])}
    # the oracle: a cell reaches the base station at the first linked step from its sighting
    oracle = np.array([next_link[s] - s for s in seen[cells]])
    got = log.base_step[cells] - seen[cells]
    assert (got == oracle).all()
    m = run.metrics()["mission"]
    # by hand: cells first seen while out of range wait for step 30 (first trip) or 96
    # (second trip); the far half of the corridor is first seen on the second trip, from
    # the step the sensor's reach passes the first trip's (x > 40.5 at step 55) to the turn (69)
    assert set(oracle[(seen[cells] > 6) & (seen[cells] < 30)]) <= set(range(1, 24))
    assert set(seen[cells][(seen[cells] > 42)]) <= set(range(55, 70))
    assert m["latency_max_s"] == 96 - 55
    assert m["latency_undelivered_frac"] == 0.0
    assert m["linked_to_base_frac"] == [want[1:].mean()]
    assert m["base_explored_final"] == m["team_explored_final"]
