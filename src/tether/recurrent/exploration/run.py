"""The grid exploration simulator under the core loop: one adapter, one recorder.

:class:`ExplorationRun` is a :class:`tether.sim.Strategy` whose world model is
an :class:`~tether.recurrent.exploration.sim.ExplorationSim`: ``step`` advances
the sim (move, sense, communicate, the policy decides), ``sense`` reports the
sim's communication graph with the base station as a fixed node after the
robots, and ``step_values`` / ``robot_values`` report the explored area and
who is connected. Positions are converted from cells to metres with the
grid's resolution and origin.

:func:`run_exploration` runs a policy on a bare occupancy array through
:func:`tether.sim.simulate` and returns the time series as arrays.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from tether.graph import components
from tether.mission.log import MissionLog
from tether.mission.metrics import mission_metrics
from tether.record import TrajectoryRecorder
from tether.recurrent.exploration.metrics import MissionMetrics, classify
from tether.recurrent.exploration.sim import (
    ExplorationConfig,
    ExplorationPolicy,
    ExplorationSim,
    GoalKind,
    random_base,
    start_cells,
)
from tether.sensing import Observation, SensorModel
from tether.sensing.robots import observation_from_pairs
from tether.sim import StepContext, Strategy, TeamState, simulate
from tether.world.grid import OccupancyGrid
from tether.world.world import World

__all__ = ["ExplorationResult", "ExplorationRun", "run_exploration"]


class ExplorationRun(Strategy):
    """Any :class:`ExplorationPolicy` on the exploration simulator, as a core strategy.

    Parameters
    ----------
    policy
        The decision-making (BS planner, Utility baseline, or your own).
    config
        Physical parameters in cells and steps.
    grid
        The true map with its metric placement.
    base_cells
        BS position in cell coordinates (snapped by the sim unless ``starts_cells``).
    starts_cells
        ``(n, 2)`` start positions in cells (default: the coarse cells nearest the BS).
    """

    name = "exploration"

    def __init__(
        self,
        policy: ExplorationPolicy,
        config: ExplorationConfig,
        grid: OccupancyGrid,
        base_cells: np.ndarray,
        starts_cells: np.ndarray | None = None,
    ) -> None:
        super().__init__()
        self.policy = policy
        self.cfg = config
        self.grid = grid
        self.base_cells = np.asarray(base_cells, dtype=float)
        self.starts_cells = starts_cells

    @classmethod
    def from_scenario(
        cls, params: Any, scenario: Any, world: World, initial: TeamState, rng: Any
    ) -> ExplorationRun:
        raise NotImplementedError("register a subclass that builds its policy from params")

    def to_m(self, cells: np.ndarray) -> np.ndarray:
        """Cell coordinates to metres (``origin + resolution * cells``)."""
        return self.grid.origin_m + cells * self.grid.resolution_m

    # -- the loop ------------------------------------------------------------------------
    def reset(self, world: World, state: TeamState, rng: np.random.Generator) -> None:
        super().reset(world, state, rng)
        self._wall_start = time.perf_counter()
        self.sim = ExplorationSim(
            self.grid.occupied, self.base_cells, self.policy, self.cfg, starts=self.starts_cells
        )
        self.policy.start(self.sim)
        self.out_steps = np.zeros(self.sim.n, dtype=int)
        self.mission = MissionMetrics(self.sim.n, self.sim.explored_fraction())
        self.states = classify(*(np.zeros(self.sim.n, bool),) * 3, self.sim.alive)
        self.dt_s = 1.0
        self.log = MissionLog(self.sim.free_region, self.sim.n)
        self._log_step(0)
        self._drain_sim_events()

    def _log_step(self, step: int) -> None:
        """Feed the mission log: what was sensed, the BS map, positions, links."""
        sim = self.sim
        pairs = np.asarray(sim.links, dtype=np.intp).reshape(-1, 2)
        robots = pairs[(pairs > 0).all(axis=1)] - 1  # links between robots (node 0: BS)
        count, _ = components(sim.n, robots)
        self.log.record(
            step,
            sim.sensed,
            sim.knowledge.global_known,
            self.to_m(sim.pos),
            sim.connected,
            count <= 1,
            base_version=sim.knowledge.global_version,
        )

    def done(self) -> bool:
        """The coverage goal (``config.coverage_goal``) is known at the base station."""
        goal = self.cfg.coverage_goal
        return goal is not None and self.log.base_explored[-1] >= goal - 1e-12

    def step(self, ctx: StepContext) -> TeamState:
        self._step = ctx.step + 1
        self.dt_s = ctx.dt_s
        sim = self.sim
        sim.step()
        self.out_steps += ~sim.connected & sim.alive
        relaying = getattr(self.policy, "relaying", None)
        self.states = classify(
            sim.moved,
            (sim.goal_kind == GoalKind.HOME) & ~sim.at_goal,
            relaying(sim) if relaying is not None else np.zeros(sim.n, bool),
            sim.alive,
        )
        self.mission.add(sim.explored_fraction(), self.states, sim.connected)
        self._log_step(self._step)
        self._drain_sim_events()
        return TeamState(self.to_m(sim.pos), np.zeros_like(sim.pos), ctx.state.fixed)

    def _drain_sim_events(self) -> None:
        self._events.extend(self.sim.events)
        self.sim.events.clear()

    def sense(
        self, state: TeamState, world: World, sensor: SensorModel | None, rng: Any
    ) -> Observation:
        """The sim's communication graph: robots ``0..n-1``, the BS as node ``n``."""
        n = self.sim.n
        pairs = np.asarray(self.sim.links, dtype=np.intp).reshape(-1, 2)
        relabel = np.r_[n, np.arange(n)]  # sim node 0 is the BS
        pairs = np.sort(relabel[pairs], axis=1)
        pairs = pairs[np.lexsort((pairs[:, 1], pairs[:, 0]))]
        nodes = np.vstack([state.positions, self.to_m(self.sim.base)[None]])
        return observation_from_pairs(nodes, pairs)

    # -- results -------------------------------------------------------------------------
    def step_values(self) -> dict[str, Any]:
        return {
            "explored_fraction": self.sim.explored_fraction(),
            "team_explored_fraction": self.log.team_explored[-1],
            "n_connected": int(self.sim.connected.sum()),
        }

    def robot_values(self) -> dict[str, np.ndarray]:
        # state: 0 moving, 1 relaying, 2 waiting, 3 returning, 4 failed (RobotState)
        return {"connected": self.sim.connected.copy(), "state": self.states.copy()}

    def metrics(self) -> dict[str, Any]:
        return {
            "final_explored_fraction": float(self.sim.explored_fraction()),
            "out_of_comm_mean_steps": float(np.mean(self.out_steps)),
            "out_of_comm_max_steps": int(np.max(self.out_steps)),
            "out_of_comm_per_robot_steps": self.out_steps.tolist(),
            **self.mission.summary(self.dt_s),
            "robots_failed": int((~self.sim.alive).sum()),
            "failures": [
                {"robot": int(r), "step": int(self.sim.failed_at[r])}
                for r in np.flatnonzero(~self.sim.alive)
            ],
            **self.policy.metrics(),
            "mission": self._mission_summary(),
            "timing_s": dict(self.sim.timing),
            "base_m": self.to_m(self.sim.base).tolist(),
            "map_cells": list(self.grid.occupied.shape),
            "resolution_m": self.grid.resolution_m,
        }

    def _mission_summary(self) -> dict[str, Any]:
        """The shared mission metrics, the coverage goal and why the run stopped."""
        out = mission_metrics(self.log, self.dt_s)
        goal = self.cfg.coverage_goal
        reached = self.done()
        grew = np.flatnonzero(np.diff(np.r_[0.0, self.log.base_explored]) > 0)
        out["coverage_goal"] = goal
        out["coverage_goal_reached"] = bool(reached)
        out["stop_reason"] = "coverage goal" if reached else "time limit"
        out["base_idle_at_end_s"] = (self.log.steps - int(grew[-1])) * self.dt_s
        return out


@dataclass
class ExplorationResult:
    """Time series of an exploration run (cells, steps ``0..T``), from its records."""

    explored: np.ndarray  # (T+1,) fraction of free area known at the BS
    connected: np.ndarray  # (T+1, n) robot linked (multi-hop) to the BS
    positions: np.ndarray  # (T+1, n, 2) cell coordinates
    n_links: np.ndarray  # (T+1,) links of the robots + BS communication graph
    lambda2: np.ndarray  # (T+1,) its unweighted algebraic connectivity
    events: list[dict[str, Any]]
    metrics: dict[str, Any]
    wall_time_s: float
    timing_s: dict[str, float]  # the sim's own split: move, sense, comm, strategy
    sim: ExplorationSim


def run_exploration(
    occupied: np.ndarray,
    policy: ExplorationPolicy,
    config: ExplorationConfig | None = None,
    base: np.ndarray | None = None,
    rng: np.random.Generator | None = None,
) -> ExplorationResult:
    """Run one exploration mission through the core loop and return its time series.

    Parameters
    ----------
    occupied
        True map ``(nx, ny)`` boolean (cell coordinates = metres here).
    policy
        An :class:`ExplorationPolicy` (e.g. ``RecurrentStrategy`` or ``UtilityStrategy``).
    config
        Physical parameters (paper defaults); ``config.steps`` steps are run.
    base
        BS position in cells; random (from ``rng``) on the largest free region if omitted.
    rng
        Random generator for the BS position.
    """
    cfg = config or ExplorationConfig()
    grid = OccupancyGrid(np.asarray(occupied, dtype=bool))
    if base is None:
        base = random_base(grid.occupied, cfg.coarse_factor, rng or np.random.default_rng(0))
    base_cells, starts = start_cells(grid.occupied, base, cfg.n_robots, cfg.coarse_factor)
    adapter = ExplorationRun(policy, cfg, grid, base_cells)
    recorder = TrajectoryRecorder()
    tic = time.perf_counter()
    result = simulate(
        World(dim=2, grid=grid),
        None,
        adapter,
        TeamState.at_rest(starts, fixed=base_cells[None]),
        dt_s=1.0,
        max_steps=cfg.steps,
        rng=rng or np.random.default_rng(0),
        recorder=recorder,
    )
    steps = recorder.step_columns()
    robots = recorder.robot_columns()
    n = cfg.n_robots
    return ExplorationResult(
        explored=np.asarray(steps["explored_fraction"]),
        connected=np.asarray(robots["connected"]).reshape(-1, n),
        positions=np.stack(recorder.positions),
        n_links=np.asarray(steps["n_links"]),
        lambda2=np.asarray(steps["lambda2"]),
        events=recorder.events,
        metrics=result.strategy_metrics,
        wall_time_s=time.perf_counter() - tic,
        timing_s=dict(adapter.sim.timing),
        sim=adapter.sim,
    )
