"""Registered exploration strategies ``recurrent`` and ``utility`` for YAML runs.

Both run the grid exploration simulator of :mod:`tether.recurrent.exploration`
under the core loop (:class:`~tether.recurrent.exploration.run.ExplorationRun`):
the team starts on the coarse cells nearest the base station (a fixed node of
the communication graph), and the policy is the BS planner
(:class:`~tether.recurrent.replanning.RecurrentStrategy`) or the Utility
baseline. Scenario fields used:

* ``world``: any 2-D scene with an occupancy grid, typically
  ``scene: map`` with ``params: {path: ..., resolution_m: 0.1}`` or the
  procedural ``office`` scene with ``dim: 2``;
* ``team.n_robots``; ``sim.max_steps`` (one step = ``sim.dt_s`` seconds);
* ``sensing.range_m``: depth-sensor range (the paper: 50 cells = 5 m);
* ``strategy.params``: see :class:`RecurrentParams` / :class:`UtilityParams`
  (physical quantities in metres and seconds, converted to cells with the
  grid resolution).
"""

from __future__ import annotations

from typing import Any, ClassVar, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from tether.errors import ScenarioError
from tether.recurrent.baseline_utility import UtilityStrategy
from tether.recurrent.exploration.run import ExplorationRun
from tether.recurrent.exploration.sim import (
    ExplorationConfig,
    ExplorationPolicy,
    random_base,
    start_cells,
)
from tether.recurrent.figures import explored_over_time, known_map
from tether.recurrent.replanning import RecurrentStrategy
from tether.registry import LINK_MODELS, STRATEGIES
from tether.sim import TeamState
from tether.world.grid import OccupancyGrid
from tether.world.world import World

__all__ = [
    "RecurrentExploration",
    "RecurrentParams",
    "UtilityExploration",
    "UtilityParams",
]


class ExplorationParams(BaseModel):
    """Physical parameters shared by both strategies (paper defaults at 0.1 m per cell)."""

    model_config = ConfigDict(extra="forbid")

    speed_m_s: float = Field(default=0.4, gt=0, description="4 cells/step at 0.1 m, 1 s steps")
    fov_deg: float = Field(default=60.0, gt=0, le=360)
    sensor_resolution_deg: float = Field(default=1.0, gt=0)
    link_model: str = "los"
    comm_range_m: float = Field(default=15.0, gt=0, description="150 cells at 0.1 m")
    coarse_cell_m: float = Field(default=0.3, gt=0, description="geodesic grid cell")
    scan_steps: int = Field(default=1, ge=1)
    base_m: list[float] | None = Field(default=None, description="BS position; random if null")


class RecurrentParams(ExplorationParams):
    """The paper's BS planner (Sec. III-VI)."""

    theta: int = Field(default=1, ge=1)
    method: Literal["apx", "ilp"] = "apx"
    delta: int = Field(default=4, ge=1)
    backend: Literal["highs", "scip"] = "highs"
    count_planning_time: bool = False
    check: bool = False
    time_limit_s: float | None = Field(default=60.0, gt=0)


class UtilityParams(ExplorationParams):
    """The Utility baseline of de Hoog et al. (return when known-area ratio < ``ratio``)."""

    ratio: float = Field(default=0.5, ge=0, le=1)


def _config(params: ExplorationParams, scenario: Any, resolution_m: float) -> ExplorationConfig:
    if params.link_model not in LINK_MODELS:
        known = ", ".join(LINK_MODELS.names())
        raise ScenarioError(
            f"{scenario.source}: strategy.params.link_model: unknown link model "
            f"{params.link_model!r}; expected one of: {known}"
        )
    factor = max(int(round(params.coarse_cell_m / resolution_m)), 1)

    def cells(metres: float) -> float:
        # round off float noise (0.4 / 0.1 = 4.000000000000001) so that the
        # paper's settings give exactly the cell values of ExplorationConfig
        return round(metres / resolution_m, 9)

    return ExplorationConfig(
        n_robots=scenario.team.n_robots,
        steps=scenario.sim.max_steps,
        speed_cells=cells(params.speed_m_s * scenario.sim.dt_s),
        fov_deg=params.fov_deg,
        sensor_range_cells=cells(scenario.sensing.range_m),
        sensor_resolution_deg=params.sensor_resolution_deg,
        link_model=params.link_model,
        link_params={"range_cells": cells(params.comm_range_m)},
        coarse_factor=factor,
        scan_steps=params.scan_steps,
    )


class _ExplorationPlugin(ExplorationRun):
    """Shared construction of the registered exploration strategies from a scenario."""

    Params: ClassVar[type[ExplorationParams]] = ExplorationParams

    @classmethod
    def make_policy(cls, params: Any) -> ExplorationPolicy:
        raise NotImplementedError

    @staticmethod
    def _grid(scenario: Any, world: World) -> OccupancyGrid:
        grid = world.grid
        if grid is None or grid.dim != 2:
            raise ScenarioError(
                f"{scenario.source}: world: exploration needs a 2-D occupancy grid "
                "(scene 'map', or a procedural scene with dim: 2)"
            )
        return grid

    @classmethod
    def initial_state(
        cls, params: Any, scenario: Any, world: World, rng: np.random.Generator
    ) -> TeamState:
        """Robots on the coarse cells nearest the BS (random unless ``base_m`` is given)."""
        grid = cls._grid(scenario, world)
        cfg = _config(params, scenario, grid.resolution_m)
        if params.base_m is not None:
            base = (np.asarray(params.base_m, float) - grid.origin_m) / grid.resolution_m
        else:
            base = random_base(grid.occupied, cfg.coarse_factor, rng)
        base, starts = start_cells(grid.occupied, base, cfg.n_robots, cfg.coarse_factor)
        to_m = grid.origin_m + np.vstack([starts, base[None]]) * grid.resolution_m
        return TeamState.at_rest(to_m[:-1], fixed=to_m[-1:])

    @classmethod
    def from_scenario(
        cls,
        params: Any,
        scenario: Any,
        world: World,
        initial: TeamState,
        rng: np.random.Generator,
    ) -> _ExplorationPlugin:
        grid = cls._grid(scenario, world)
        cfg = _config(params, scenario, grid.resolution_m)
        base_cells = (np.asarray(initial.fixed[0]) - grid.origin_m) / grid.resolution_m
        return cls(cls.make_policy(params), cfg, grid, base_cells)

    def figures(self, recording: Any, world: World, dt_s: float) -> dict[str, Any]:
        steps = recording.step_columns()
        t = np.asarray(steps["step"]) * dt_s
        trails = np.stack(recording.positions)
        explored = np.asarray(steps["explored_fraction"])
        last = recording.robot_values[-1] if recording.robot_values else {}
        title = (
            f"{self.name}: map known at the base station, t = {t[-1]:g} s "
            f"({100 * explored[-1]:.0f} % explored)"
        )
        return {
            "explored.png": explored_over_time(
                t,
                explored,
                np.asarray(steps["n_connected"]),
                n_robots=trails.shape[1],
                title=f"{self.name}: explored area known at the base station",
            ),
            "map.png": known_map(
                self.grid,
                self.sim.knowledge.global_known,
                trails,
                self.to_m(self.sim.base),
                connected=last.get("connected"),
                title=title,
            ),
        }


@STRATEGIES.register("recurrent")
class RecurrentExploration(_ExplorationPlugin):
    """Asynchronous exploration under recurrent connectivity (Banfi et al. 2016)."""

    name = "recurrent"
    Params = RecurrentParams

    @classmethod
    def make_policy(cls, params: RecurrentParams) -> RecurrentStrategy:
        return RecurrentStrategy(
            theta=params.theta,
            method=params.method,
            delta=params.delta,
            backend=params.backend,
            count_planning_time=params.count_planning_time,
            check=params.check,
            time_limit_s=params.time_limit_s,
        )


@STRATEGIES.register("utility")
class UtilityExploration(_ExplorationPlugin):
    """The Utility baseline (de Hoog et al.) the paper compares with."""

    name = "utility"
    Params = UtilityParams

    @classmethod
    def make_policy(cls, params: UtilityParams) -> UtilityStrategy:
        return UtilityStrategy(ratio=params.ratio)
