"""Registered exploration strategies ``recurrent`` and ``utility`` for YAML runs.

These strategies have their own time loop (the grid exploration simulator of
:mod:`tether.recurrent.exploration`), so instead of the continuous-space
``Strategy`` protocol they provide ``run_scenario(scenario, out_dir, rng)``,
which the runner calls. Scenario fields used:

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

import time
from pathlib import Path
from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from tether.errors import ScenarioError
from tether.graph import pairs_within
from tether.recurrent.baseline_utility import UtilityStrategy
from tether.recurrent.exploration import (
    ExplorationConfig,
    ExplorationResult,
    ExplorationSim,
    random_base,
)
from tether.recurrent.replanning import RecurrentStrategy
from tether.registry import LINK_MODELS, STRATEGIES

__all__ = [
    "RecurrentExploration",
    "RecurrentParams",
    "UtilityExploration",
    "UtilityParams",
    "run_summary",
    "write_run",
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


def run_summary(
    result: ExplorationResult,
    *,
    scenario: str,
    strategy: str,
    seed: int,
    n_robots: int,
    dt_s: float = 1.0,
    collision_distance_cells: float = 0.0,
) -> dict[str, Any]:
    """Scalar results of an exploration run (the ``summary.json`` keys).

    Besides the exploration metrics, the core keys of every tether run, for the
    communication graph of the robots and the BS: ``connected_all_steps`` (every
    robot linked to the BS at every step; recurrent connectivity allows otherwise),
    ``min_links``, ``min_lambda2`` (unweighted) and ``collisions`` (robot pairs
    closer than ``collision_distance_cells``, summed over steps: robots are points
    here and do not avoid each other).
    """
    steps = len(result.explored) - 1
    out_steps = (~result.connected[1:]).sum(axis=0) if steps else np.zeros(n_robots)
    collisions = 0
    if collision_distance_cells > 0:
        collisions = sum(len(pairs_within(p, collision_distance_cells)) for p in result.positions)
    graph = {}
    if result.n_links is not None and result.lambda2 is not None:
        graph = {
            "min_links": int(result.n_links.min()),
            "min_lambda2": float(result.lambda2.min()),
        }
    return {
        "scenario": scenario,
        "strategy": strategy,
        "seed": seed,
        "n_robots": n_robots,
        "sim_time_s": steps * dt_s,
        "steps": steps,
        "wall_time_s": result.wall_time_s,
        "connected_all_steps": bool(result.connected.all()),
        **graph,
        "collisions": int(collisions),
        "final_explored_fraction": float(result.explored[-1]),
        "out_of_comm_mean_steps": float(np.mean(out_steps)),
        "out_of_comm_max_steps": int(np.max(out_steps)),
        "out_of_comm_per_robot_steps": out_steps.tolist(),
        **result.metrics,
        "timing_s": result.timing_s,
    }


def write_run(
    folder: Any,
    result: ExplorationResult,
    summary: dict[str, Any],
    *,
    resolution_m: float = 1.0,
    origin_m: np.ndarray | None = None,
    record_every: int = 1,
    figures: bool = False,
    sim: ExplorationSim | None = None,
) -> None:
    """Write an exploration run into a :class:`tether.record.RunFolder`.

    Files: ``steps.parquet`` (step, explored fraction, robots connected),
    ``robots.parquet`` (step, robot, x_m, y_m, connected), ``events.parquet``
    (plans with planning times, aborts, returns), ``summary.json`` and, with
    ``figures``, ``figures/explored.png`` and ``figures/map.png``.
    """
    from tether.record import provenance

    origin = np.zeros(2) if origin_m is None else np.asarray(origin_m, float)
    steps = np.arange(len(result.explored))
    folder.write_table(
        "steps.parquet",
        {
            "step": steps,
            "explored_fraction": result.explored,
            "n_connected": result.connected.sum(axis=1),
        },
    )
    keep = steps[:: max(int(record_every), 1)]
    pos = result.positions[keep]  # (T, n, 2) cells
    t, n, _ = pos.shape
    world = origin + pos * resolution_m
    folder.write_table(
        "robots.parquet",
        {
            "step": np.repeat(keep, n),
            "robot": np.tile(np.arange(n), t),
            "x_m": world[:, :, 0].ravel(),
            "y_m": world[:, :, 1].ravel(),
            "connected": result.connected[keep].ravel(),
        },
    )
    folder.write_rows("events.parquet", result.events)
    folder.write_json("summary.json", {**summary, "provenance": provenance()})
    if figures:
        from tether.recurrent.report import plot_map, plot_run

        folder.save_figure(plot_run(result), "explored.png")
        if sim is not None:
            folder.save_figure(plot_map(sim, result), "map.png")


def _run(cls: type, strategy: Any, scenario: Any, out_dir: Path, rng: np.random.Generator) -> dict:
    from tether.record import RunFolder
    from tether.runner import build_world

    params = cls.Params.model_validate(scenario.strategy.params)
    world = build_world(scenario, rng)
    grid = world.grid
    if grid is None or grid.dim != 2:
        raise ScenarioError(
            f"{scenario.source}: world: exploration needs a 2-D occupancy grid "
            "(scene 'map', or a procedural scene with dim: 2)"
        )
    cfg = _config(params, scenario, grid.resolution_m)
    occupied = grid.occupied
    if params.base_m is not None:
        base = (np.asarray(params.base_m, float) - grid.origin_m) / grid.resolution_m
    else:
        base = random_base(occupied, cfg.coarse_factor, rng)
    tic = time.perf_counter()
    sim = ExplorationSim(occupied, base, strategy, cfg)
    strategy.start(sim)
    for _ in range(cfg.steps):
        sim.step()
    result = sim.result(time.perf_counter() - tic)
    summary = run_summary(
        result,
        scenario=scenario.name,
        strategy=scenario.strategy.name,
        seed=int(scenario.seed),
        n_robots=cfg.n_robots,
        dt_s=scenario.sim.dt_s,
        collision_distance_cells=scenario.sim.collision_distance_m / grid.resolution_m,
    )
    summary["base_m"] = (grid.origin_m + sim.base * grid.resolution_m).tolist()
    summary["map_cells"] = list(occupied.shape)
    summary["resolution_m"] = grid.resolution_m
    write_run(
        RunFolder(out_dir),
        result,
        summary,
        resolution_m=grid.resolution_m,
        origin_m=grid.origin_m,
        record_every=scenario.output.record_every,
        figures=scenario.output.figures,
        sim=sim,
    )
    return summary


@STRATEGIES.register("recurrent")
class RecurrentExploration:
    """Asynchronous exploration under recurrent connectivity (Banfi et al. 2016)."""

    Params = RecurrentParams

    @classmethod
    def make(cls, params: RecurrentParams) -> RecurrentStrategy:
        return RecurrentStrategy(
            theta=params.theta,
            method=params.method,
            delta=params.delta,
            backend=params.backend,
            count_planning_time=params.count_planning_time,
            check=params.check,
            time_limit_s=params.time_limit_s,
        )

    @classmethod
    def run_scenario(cls, scenario: Any, out_dir: Path, rng: np.random.Generator) -> dict:
        params = cls.Params.model_validate(scenario.strategy.params)
        return _run(cls, cls.make(params), scenario, Path(out_dir), rng)


@STRATEGIES.register("utility")
class UtilityExploration:
    """The Utility baseline (de Hoog et al.) the paper compares with."""

    Params = UtilityParams

    @classmethod
    def make(cls, params: UtilityParams) -> UtilityStrategy:
        return UtilityStrategy(ratio=params.ratio)

    @classmethod
    def run_scenario(cls, scenario: Any, out_dir: Path, rng: np.random.Generator) -> dict:
        params = cls.Params.model_validate(scenario.strategy.params)
        return _run(cls, cls.make(params), scenario, Path(out_dir), rng)
