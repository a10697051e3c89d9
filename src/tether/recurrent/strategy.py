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

from typing import Annotated, Any, ClassVar, Literal

import numpy as np
from pydantic import BaseModel, Field

from tether.config import MAX_LENGTH_M, Coordinate, finite_strict
from tether.errors import ScenarioError
from tether.limits import format_bytes, memory_budget_bytes
from tether.paths.geodesic import CoarseGrid
from tether.recurrent import checks
from tether.recurrent.baseline_utility import UtilityStrategy
from tether.recurrent.checks import MAX_RAY_SAMPLES
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
    "FailureParams",
    "ExplorationParams",
    "ExplorationPlugin",
    "RecurrentExploration",
    "RecurrentParams",
    "SignalParams",
    "UtilityExploration",
    "UtilityParams",
]


class SignalParams(BaseModel):
    """The ``signal`` link model (:class:`tether.sensing.links.SignalLinks`)."""

    model_config = finite_strict()

    ref_power_dbm: float = Field(
        default=-40.0, ge=-300, le=300, description="received power at ref_distance_m"
    )
    ref_distance_m: float = Field(
        default=1.0, gt=0, le=MAX_LENGTH_M, description="distance of ref_power_dbm"
    )
    exponent: float = Field(default=2.5, gt=0, le=20, description="path-loss exponent")
    wall_loss_db: float = Field(default=3.0, ge=0, le=1000, description="per wall cell crossed")
    cutoff_dbm: float = Field(default=-70.0, ge=-300, le=300, description="receive threshold")


class FailureParams(BaseModel):
    """Robots that fail (stop, sense nothing, drop their links) during the run."""

    model_config = finite_strict()

    at_s: dict[int, Annotated[float, Field(ge=0, le=1e9)]] = Field(
        default_factory=dict, description="robot -> failure time"
    )
    random: int = Field(
        default=0, ge=0, le=1_000_000, description="robots failing at uniform random times"
    )
    window_s: tuple[float, float] | None = Field(
        default=None, description="random failure times drawn from [t0, t1] (default: the run)"
    )


class ExplorationParams(BaseModel):
    """Physical parameters shared by both strategies (paper defaults at 0.1 m per cell)."""

    model_config = finite_strict()

    speed_m_s: float = Field(
        default=0.4, gt=0, le=MAX_LENGTH_M, description="robot speed (4 cells per 1 s at 0.1 m)"
    )
    fov_deg: float = Field(default=60.0, gt=0, le=360, description="depth sensor's field of view")
    sensor_resolution_deg: float = Field(
        default=1.0, ge=0.01, le=360, description="angle between the depth sensor's rays"
    )
    link_model: str = Field(default="los", description="communication links: los, disk, signal")
    comm_range_m: float = Field(
        default=15.0, gt=0, le=MAX_LENGTH_M, description="link range of los and disk"
    )
    coarse_cell_m: float = Field(
        default=0.3, gt=0, le=MAX_LENGTH_M, description="geodesic grid cell"
    )
    scan_steps: int = Field(
        default=1, ge=1, le=10_000, description="steps a full turn at a frontier takes"
    )
    base_m: list[Coordinate] | None = Field(default=None, description="BS position; random if null")
    signal: SignalParams = Field(default_factory=SignalParams, description="link_model: signal")
    failures: FailureParams = Field(
        default_factory=FailureParams, description="robots that fail during the run"
    )
    coverage_goal: float | None = Field(
        default=None,
        gt=0,
        le=1,
        description="end the run once the base station knows this share of the reachable "
        "area (null: run sim.max_steps)",
    )


class RecurrentParams(ExplorationParams):
    """The paper's BS planner (Sec. III-VI)."""

    theta: int = Field(
        default=1, ge=1, le=100_000, description="replan when this many robots are ready"
    )
    method: Literal["apx", "ilp"] = Field(
        default="apx", description="configuration solver: Algorithm 1 or the exact ILP"
    )
    delta: int = Field(default=4, ge=1, le=100_000, description="APX's parameter delta")
    backend: Literal["highs", "scip"] = Field(default="highs", description="the ILP's solver")
    count_planning_time: bool = Field(
        default=False, description="robots wait out the planning time (the paper's Fig. 4a)"
    )
    check: bool = Field(default=False, description="check every plan, record violations")
    time_limit_s: float | None = Field(
        default=10.0, gt=0, le=1e7, description="per-plan budget of the ILP (APX as fallback)"
    )
    relay_binding: Literal["assigned", "frontiers"] = Field(
        default="assigned",
        description="P_f for every robot sent to a new goal, or (the paper) for frontiers only",
    )


class UtilityParams(ExplorationParams):
    """The Utility baseline of de Hoog et al. (return when known-area ratio < ``ratio``)."""

    ratio: float = Field(
        default=0.5, ge=0, le=1, description="return when the known-area ratio falls below"
    )
    coordination: Literal["greedy", "none"] = Field(
        default="greedy",
        description="greedy: joint best-pair assignment inside communicating groups "
        "(de Hoog et al.'s MRESim); none: every robot on its own",
    )


def _config(
    params: ExplorationParams, scenario: Any, resolution_m: float, shape: Any = None
) -> ExplorationConfig:
    """The simulator's parameters in cells; ranges beyond the map's diagonal are cut to it.

    ``shape`` is the grid's ``(nx, ny)``; without it ranges are not cut.
    """
    if params.link_model not in LINK_MODELS:
        known = ", ".join(LINK_MODELS.names())
        raise ScenarioError(
            f"{scenario.source}: strategy.params.link_model: unknown link model "
            f"{params.link_model!r}; expected one of: {known}"
        )
    factor = checks.coarse_factor(params, scenario, resolution_m, shape)
    # no ray or link reaches farther than the map's diagonal
    diagonal = np.inf if shape is None else float(np.hypot(*shape)) + 1.0

    def cells(metres: float) -> float:
        # round off float noise (0.4 / 0.1 = 4.000000000000001) so that the
        # paper's settings give exactly the cell values of ExplorationConfig
        return round(metres / resolution_m, 9)

    sensor_cells = min(cells(scenario.sensing.range_m), diagonal)
    rays = int(np.ceil(360.0 / params.sensor_resolution_deg)) + 1
    if rays * (sensor_cells / 0.5 + 1) > MAX_RAY_SAMPLES:
        raise ScenarioError(
            f"{scenario.source}: strategy.params.sensor_resolution_deg: {rays:,} rays of "
            f"{sensor_cells:.0f} cells are more than {MAX_RAY_SAMPLES:,} samples per scan; "
            "raise sensor_resolution_deg or lower sensing.range_m"
        )
    speed_cells = cells(params.speed_m_s * scenario.sim.dt_s)
    checks.check_speed(params, scenario, resolution_m, speed_cells)
    checks.check_ref_distance(params, scenario, resolution_m, cells(params.signal.ref_distance_m))
    if isinstance(params, RecurrentParams):  # it plans from the BS's known coarse cell
        checks.check_base_sensed(params, scenario, resolution_m, factor, sensor_cells)
    return ExplorationConfig(
        n_robots=scenario.team.n_robots,
        steps=scenario.sim.max_steps,
        speed_cells=speed_cells,
        fov_deg=params.fov_deg,
        sensor_range_cells=sensor_cells,
        sensor_resolution_deg=params.sensor_resolution_deg,
        link_model=params.link_model,
        link_params=_link_params(params, cells, diagonal),
        coarse_factor=factor,
        scan_steps=params.scan_steps,
        coverage_goal=params.coverage_goal,
    )


def _base_cells(base_m: list[float], grid: OccupancyGrid, source: str) -> np.ndarray:
    """The base station's cell coordinates; refused outside the map or in an obstacle."""
    field = f"{source}: strategy.params.base_m"
    if len(base_m) != 2:
        raise ScenarioError(f"{field}: expected [x, y] in metres (got {len(base_m)} numbers)")
    lo, hi = grid.bounds_m
    point = np.asarray(base_m, dtype=float)
    if not np.all((point >= lo) & (point < hi)):
        raise ScenarioError(
            f"{field}: {point.tolist()} is outside the map ({lo[0]:g}..{hi[0]:g} x "
            f"{lo[1]:g}..{hi[1]:g} m); give a point on the map"
        )
    if grid.is_occupied(point[None])[0]:
        raise ScenarioError(
            f"{field}: {point.tolist()} is inside an obstacle; move it into free space"
        )
    return (point - grid.origin_m) / grid.resolution_m


def _check_memory(n_robots: int, grid: OccupancyGrid, source: str) -> None:
    """Every robot keeps its own map of the grid: refuse a team that would not fit."""
    need = n_robots * grid.occupied.size * 3  # local maps, plus what exchanging them copies
    budget = memory_budget_bytes()
    if need > budget:
        raise ScenarioError(
            f"{source}: team.n_robots: {n_robots:,} robots each keeping a map of "
            f"{grid.occupied.size:,} cells need about {format_bytes(need)}, more than the "
            f"{format_bytes(budget)} allowed here; use fewer robots or a coarser map"
        )


def _link_params(params: ExplorationParams, cells: Any, diagonal: float) -> dict[str, Any]:
    if params.link_model != "signal":
        return {"range_cells": min(cells(params.comm_range_m), diagonal)}
    sig = params.signal.model_dump()
    sig["ref_distance_cells"] = cells(sig.pop("ref_distance_m"))
    return sig


def failure_schedule(
    params: FailureParams, n_robots: int, steps: int, dt_s: float, rng: np.random.Generator
) -> dict[int, int]:
    """Robot -> failure step: the given times, then ``random`` other robots at random steps."""
    out: dict[int, int] = {}
    for r, t in params.at_s.items():
        if not 0 <= r < n_robots:
            raise ValueError(f"failures.at_s: no robot {r} in a team of {n_robots}")
        out[int(r)] = max(int(round(t / dt_s)), 1)
    others = [r for r in range(n_robots) if r not in out]
    if params.random > len(others):
        raise ValueError(
            f"failures.random: {params.random} robots cannot fail at random in a team of "
            f"{n_robots} ({len(out)} fail at given times); use at most {len(others)}"
        )
    k = params.random
    if k:
        lo, hi = params.window_s if params.window_s is not None else (dt_s, steps * dt_s)
        lo_step, hi_step = max(int(round(lo / dt_s)), 1), max(int(round(hi / dt_s)), 1)
        for r in rng.choice(others, size=k, replace=False).tolist():
            out[int(r)] = int(rng.integers(lo_step, max(hi_step, lo_step) + 1))
    return out


class ExplorationPlugin(ExplorationRun):
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
        cfg = _config(params, scenario, grid.resolution_m, grid.shape)
        src = scenario.source
        coarse = CoarseGrid(~grid.occupied, cfg.coarse_factor)
        if coarse.n_nodes == 0:
            raise ScenarioError(
                f"{src}: world: the map has no free square of coarse_cell_m = "
                f"{params.coarse_cell_m:g} m for the team to move on; use a map with free "
                "space, or a smaller strategy.params.coarse_cell_m"
            )
        if params.base_m is not None:
            base = _base_cells(params.base_m, grid, src)
        else:
            base = random_base(grid.occupied, cfg.coarse_factor, rng)
        region = coarse.components == coarse.components[coarse.nearest_node(base)]
        if cfg.n_robots > region.sum():
            raise ScenarioError(
                f"{src}: team.n_robots: {cfg.n_robots:,} robots, but the free area around the "
                f"base station has only {int(region.sum()):,} cells of {params.coarse_cell_m:g} m "
                "to start on; use fewer robots or a larger map"
            )
        _check_memory(cfg.n_robots, grid, src)
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
    ) -> ExplorationPlugin:
        grid = cls._grid(scenario, world)
        cfg = _config(params, scenario, grid.resolution_m, grid.shape)
        try:
            cfg.failures = failure_schedule(
                params.failures, cfg.n_robots, cfg.steps, scenario.sim.dt_s, rng
            )
        except ValueError as exc:
            raise ScenarioError(f"{scenario.source}: strategy.params.{exc}") from None
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
class RecurrentExploration(ExplorationPlugin):
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
            relay_binding=params.relay_binding,
        )


@STRATEGIES.register("utility")
class UtilityExploration(ExplorationPlugin):
    """The Utility baseline (de Hoog et al.) the paper compares with."""

    name = "utility"
    Params = UtilityParams

    @classmethod
    def make_policy(cls, params: UtilityParams) -> UtilityStrategy:
        return UtilityStrategy(ratio=params.ratio, coordination=params.coordination)
