"""Build a scenario's world, team and strategy; run it; write its run folder.

This is the Python API behind ``tether run``::

    from tether.runner import run
    outcome = run("silent_demo")            # a built-in name or a YAML path
    print(outcome.path, outcome.summary["connected_all_steps"])
"""

from __future__ import annotations

import datetime as dt
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import ValidationError

from tether.config import Scenario, format_validation_error, load_scenario
from tether.errors import MapError, ScenarioError, TetherError
from tether.graph import is_connected
from tether.plugins import load_builtins
from tether.record import TrajectoryRecorder, summarize
from tether.registry import SCENES, STRATEGIES
from tether.runfolder import RunFolder
from tether.sensing import SensorModel, sensed_pairs
from tether.sim import Strategy, TeamState, simulate
from tether.team import initial_positions
from tether.viz.plots import link_range_m, links_over_time, team_snapshot
from tether.world.scenes import make_scene
from tether.world.world import World

load_builtins()


@dataclass
class Built:
    """A scenario turned into objects, ready to simulate."""

    scenario: Scenario
    world: World
    sensor: SensorModel
    initial: TeamState
    strategy: Strategy
    rng: np.random.Generator


@dataclass
class RunOutcome:
    path: Path
    summary: dict[str, Any]


def build_world(scenario: Scenario, rng: np.random.Generator) -> World:
    """The scenario's world from the scene registry (``free``, ``map``, ``town``, ...)."""
    src, cfg = scenario.source, scenario.world
    if cfg.scene not in SCENES:
        raise ScenarioError(
            f"{src}: world.scene: unknown scene {cfg.scene!r}; expected one of: "
            f"{', '.join(SCENES.names())}"
        )
    params = dict(cfg.params)
    if cfg.scene == "free":
        params.setdefault("dim", cfg.dim)
    field = "world.params"
    for key in ("path", "file"):
        if key in params:
            field = f"world.params.{key}"
            resolved = scenario.resolve_path(params[key])
            if not resolved.exists():
                raise ScenarioError(
                    f"{src}: {field}: {params[key]}: file not found beside the scenario "
                    f"({scenario.base_dir}) or from the current directory; give a path "
                    "relative to one of them or an absolute one"
                )
            params[key] = str(resolved)
    try:
        world = make_scene(cfg.scene, rng, **params)
    except (MapError, ScenarioError) as exc:
        raise ScenarioError(f"{src}: {field}: {exc}") from None
    if world.dim != cfg.dim:
        raise ScenarioError(
            f"{src}: world.dim: scene {cfg.scene!r} is {world.dim}-D; set dim: {world.dim}"
        )
    return world


def make_sensor(scenario: Scenario) -> SensorModel:
    s = scenario.sensing
    return SensorModel(
        range_m=s.range_m,
        body_radius_m=s.body_radius_m,
        occlusion=s.occlusion,
        radial_error_m=s.radial_error_m,
        angular_error_rad=s.angular_error_rad,
        noise=s.noise,
    )


def strategy_class(scenario: Scenario) -> type[Strategy]:
    name = scenario.strategy.name
    if name not in STRATEGIES:
        raise ScenarioError(
            f"{scenario.source}: strategy.name: unknown strategy {name!r}; expected one of: "
            f"{', '.join(STRATEGIES.names())}"
        )
    return STRATEGIES.get(name)


def strategy_params(scenario: Scenario, cls: type) -> Any:
    try:
        return cls.Params.model_validate(scenario.strategy.params)
    except ValidationError as exc:
        raise ScenarioError(
            format_validation_error(scenario.source, exc, prefix="strategy.params")
        ) from None


def build(scenario: Scenario, seed: int | None = None) -> Built:
    """Turn a validated scenario into world, sensor, team and strategy (no simulation).

    Everything ``tether validate`` checks happens here, before any simulation:
    the strategy's parameters, the world, the initial team and whatever the
    strategy's ``from_scenario`` checks.
    """
    rng = np.random.default_rng(scenario.seed if seed is None else seed)
    cls = strategy_class(scenario)
    params = strategy_params(scenario, cls)
    world = build_world(scenario, rng)
    sensor = make_sensor(scenario)
    initial = cls.initial_state(params, scenario, world, rng)
    if initial is None:
        initial = TeamState.at_rest(place_team(scenario, world, sensor, rng))
    strategy = cls.from_scenario(params, scenario, world, initial, rng)
    return Built(scenario, world, sensor, initial, strategy, rng)


def place_team(
    scenario: Scenario, world: World, sensor: SensorModel, rng: np.random.Generator
) -> np.ndarray:
    """The team of ``team.init``: in free space and connected in the sensing graph."""
    try:
        positions = initial_positions(
            scenario.team.init, scenario.team.n_robots, world, rng, scenario.sensing.range_m
        )
    except ValueError as exc:
        raise ScenarioError(f"{scenario.source}: team.init: {exc}") from None
    bad = ~world.points_free(positions)
    if bad.any():
        k = int(np.argmax(bad))
        raise ScenarioError(
            f"{scenario.source}: team.init: robot {k} at {positions[k].tolist()} is inside an "
            "obstacle or outside the world; move the team into free space"
        )
    pairs = sensed_pairs(positions, sensor, world)
    if not is_connected(len(positions), pairs):
        raise ScenarioError(
            f"{scenario.source}: team.init: the initial team is not connected with "
            f"sensing.range_m={sensor.range_m}; place robots closer (spacing_m) or raise the range"
        )
    return positions


def default_run_dir(scenario: Scenario, seed: int, root: str | Path | None = None) -> Path:
    stamp = dt.datetime.now().strftime("%Y%m%d-%H%M%S-%f")
    return Path(root or scenario.output.dir) / f"{scenario.name}-s{seed}-{stamp}"


def run(
    scenario: Scenario | str | Path,
    *,
    out_dir: str | Path | None = None,
    seed: int | None = None,
    figures: bool | None = None,
) -> RunOutcome:
    """Run one scenario and write its run folder; returns the folder and the summary.

    The folder is committed as a whole (:class:`tether.runfolder.RunFolder`):
    ``summary.json`` is written last, and the folder appears at ``out_dir``
    only when the run and its figures are complete.
    """
    if not isinstance(scenario, Scenario):
        scenario = load_scenario(scenario)
    if seed is not None and seed != scenario.seed:  # the run folder records the seed it ran
        source, base_dir = scenario.source, scenario.base_dir
        scenario = scenario.model_copy(update={"seed": seed})
        scenario._source, scenario._base_dir = source, base_dir
    seed = scenario.seed
    built = build(scenario, seed)
    path = Path(out_dir) if out_dir is not None else default_run_dir(scenario, seed)
    folder = RunFolder(path)
    try:
        recorder = TrajectoryRecorder(every=scenario.output.record_every)
        start = time.perf_counter()
        result = simulate(
            built.world,
            built.sensor,
            built.strategy,
            built.initial,
            dt_s=scenario.sim.dt_s,
            max_steps=scenario.sim.max_steps,
            rng=built.rng,
            collision_distance_m=scenario.sim.collision_distance_m,
            recorder=recorder,
        )
        wall = time.perf_counter() - start
        folder.write_yaml("scenario.yaml", scenario.model_dump(mode="json"))
        folder.write_table("steps.parquet", recorder.step_columns())
        folder.write_table("robots.parquet", recorder.robot_columns())
        folder.write_table("links.parquet", recorder.link_columns())
        folder.write_rows("events.parquet", recorder.events)
        if scenario.output.figures if figures is None else figures:
            for name, fig in run_figures(built, recorder).items():
                folder.save_figure(fig, name)
        summary = summarize(scenario, seed, result, wall)
        folder.commit(summary)
    except BaseException:
        folder.abort()
        raise
    return RunOutcome(path, summary)


def run_figures(built: Built, recorder: TrajectoryRecorder) -> dict[str, Any]:
    """The standard figures of a run (links over time, snapshots), then the strategy's own."""
    figs: dict[str, Any] = {}
    steps = recorder.step_columns()
    if not steps:
        return figs
    dt_s = built.scenario.sim.dt_s
    t = np.asarray(steps["step"]) * dt_s
    n = built.initial.n
    own = built.strategy.figures(recorder, built.world, dt_s)  # these replace standard ones
    name = built.scenario.name
    if "links.png" not in own:
        n_nodes = n + (0 if recorder.fixed is None else len(recorder.fixed))
        links = {name: (t, np.asarray(steps["n_links"]))}
        figs["links.png"] = links_over_time(links, n_nodes, title=f"{name}: links over time")
    if "snapshot.png" not in own:
        params = strategy_params(built.scenario, type(built.strategy))
        snap = team_snapshot(
            recorder,
            built.world,
            dt_s,
            range_m=link_range_m(built.scenario, params),
            title=f"{name}: the team at three instants",
        )
        if snap is not None:
            figs["snapshot.png"] = snap
    figs.update(own)
    return figs


__all__ = ["Built", "RunOutcome", "TetherError", "build", "build_world", "run", "run_figures"]
