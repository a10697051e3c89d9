"""Build a scenario's world, team and strategy; run it; write its run folder.

This is the Python API behind ``tether run``::

    from tether.runner import run
    outcome = run("silent_demo")            # a built-in name or a YAML path
    print(outcome.path, outcome.summary["connected_all_steps"])
"""

from __future__ import annotations

import copy
import datetime as dt
import inspect
import time
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import ValidationError

from tether.config import (
    MAX_SEED,
    InitConfig,
    Scenario,
    format_validation_error,
    load_scenario,
    scenario_from_dict,
    set_dotted,
    sweep_spec,
)
from tether.errors import OutputError, ScenarioError, TetherError
from tether.graph import is_connected
from tether.plugins import load_builtins
from tether.record import (
    TrajectoryRecorder,
    check_run_size,
    check_size_before_work,
    summarize,
)
from tether.registry import SCENES, STRATEGIES
from tether.runfolder import RunFolder
from tether.scenario_world import STAND_IN_KEY, build_world, keep_scene_files, scene_files
from tether.sensing import SensorModel, sensed_pairs
from tether.sim import RunResult, Strategy, TeamState, simulate
from tether.suggest import did_you_mean
from tether.sweepspec import canonical, value_key
from tether.team import initial_positions
from tether.viz.plots import link_range_m, links_over_time, team_snapshot
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
    #: the memory the run needs, estimated before it starts (bytes)
    memory_bytes: float = 0.0


@dataclass
class RunOutcome:
    path: Path
    summary: dict[str, Any]


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
            f"{scenario.source}: strategy.name: unknown strategy {name!r}"
            f"{did_you_mean(name, STRATEGIES.names())}; expected one of: "
            f"{', '.join(STRATEGIES.names())} (or your own module: --plugin FILE.py)"
        )
    return STRATEGIES.get(name)


def strategy_params(scenario: Scenario, cls: type) -> Any:
    try:
        return cls.Params.model_validate(scenario.strategy.params)
    except ValidationError as exc:
        raise ScenarioError(
            format_validation_error(scenario.source, exc, "strategy.params", cls.Params)
        ) from None


def as_scenario(scenario: Scenario | dict[str, Any] | str | Path) -> Scenario:
    """A :class:`Scenario` from a scenario, a dict, a built-in name or a YAML path."""
    if isinstance(scenario, Scenario):
        return scenario
    if isinstance(scenario, dict):
        return scenario_from_dict(scenario, "<scenario dict>")
    if isinstance(scenario, str | Path):
        return load_scenario(scenario)
    raise TypeError(
        "scenario must be a Scenario, a dict, a built-in scenario name or a YAML path "
        f"(got {type(scenario).__name__})"
    )


def check_seed(seed: Any) -> int | None:
    """``seed`` if it is ``None`` or an integer in ``[0, 2**63 - 1]``; else a clear error."""
    if seed is None:
        return None
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer):
        raise TypeError(f"seed must be an integer (got {type(seed).__name__} {seed!r})")
    if not 0 <= seed <= MAX_SEED:
        raise ValueError(f"seed must be an integer in [0, 2**63 - 1] (got {seed})")
    return int(seed)


def check_sweep(scenario: Scenario, cls: type[Strategy]) -> dict[str, list[Any]]:
    """Every row of every ``sweep:`` group gives a valid scenario; the axes, normalised.

    Checked row by row (linear in the number of values, not the grid; the axes of a
    ``zip`` group together): the axis must name a scenario key (for
    ``strategy.params.*`` a parameter of the strategy, for ``world.params.*`` one of
    the scene) and each value must pass validation. Values are normalised to what
    validation made of them (``'15.0'`` -> ``15.0`` for a float field; see
    :func:`tether.sweepspec.canonical` elsewhere), and two rows that normalise alike
    are refused (they would be one trial twice).

    Returns
    -------
    dict of str to list
        The axes in file order with their normalised values.
    """
    spec = sweep_spec(scenario)
    if not spec.axes:
        return {}
    src = scenario.source
    base = scenario.model_dump(mode="json")
    base.pop("sweep", None)
    normal: dict[str, list[Any]] = {key: [] for key in spec.axes}
    for group in spec.groups:
        field = f"sweep.{group[0]}"
        seen: dict[str, Any] = {}
        for row in spec.group_rows(group):
            data = copy.deepcopy(base)
            for key, value in row.items():
                set_dotted(data, key, value)
            shown = _short(row[group[0]] if len(group) == 1 else row)
            try:
                trial = scenario_from_dict(data, "", scenario.base_dir)
                trial_cls = strategy_class(trial) if data["strategy"] != base["strategy"] else cls
                params = strategy_params(trial, trial_cls)
                for key in group:
                    _check_scene_parameter(trial, key)
            except ScenarioError as exc:
                problem = str(exc).removeprefix(": ")
                raise ScenarioError(
                    f"{src}: {field}: value {shown} is refused ({problem})"
                ) from None
            values = {key: _normalised(trial, params, key, row[key]) for key in group}
            text = value_key(values)
            if text in seen:
                raise ScenarioError(
                    f"{src}: {field}: values {_short(seen[text])} and {shown} are one value "
                    "(the same trial twice); remove one"
                )
            seen[text] = row[group[0]] if len(group) == 1 else row
            for key, value in values.items():
                normal[key].append(value)
    return normal


def _normalised(trial: Scenario, params: Any, key: str, value: Any) -> Any:
    """The value of ``key`` as validation made it (``'15.0'`` -> ``15.0``), else canonical."""
    if key.startswith("strategy.params.") and hasattr(params, "model_dump"):
        node: Any = params.model_dump(mode="json")
        parts = key.split(".")[2:]
    elif key.startswith(("strategy.params.", "world.params.")):
        return canonical(value)
    else:
        node, parts = trial.model_dump(mode="json"), key.split(".")
    for part in parts:
        if not isinstance(node, dict) or part not in node:
            return canonical(value)
        node = node[part]
    return node


def _short(value: Any, limit: int = 40) -> str:
    text = repr(value)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _check_scene_parameter(scenario: Scenario, key: str) -> None:
    """A swept ``world.params.X`` must be a parameter of the scene."""
    parts = key.split(".")
    if parts[:2] != ["world", "params"] or len(parts) < 3 or scenario.world.scene not in SCENES:
        return
    factory = SCENES.get(scenario.world.scene)
    accepted = [p for p in inspect.signature(factory).parameters if p != "rng"] + ["seed"]
    accepted += [STAND_IN_KEY] if "path" in accepted else []
    if parts[2] not in accepted:
        raise ScenarioError(
            f": world.params.{parts[2]}: scene {scenario.world.scene!r} has no such parameter; "
            f"accepted: {', '.join(accepted)}"
        )


def build(scenario: Scenario | dict[str, Any] | str | Path, seed: int | None = None) -> Built:
    """Turn a scenario into world, sensor, team and strategy (no simulation).

    ``scenario`` may be a :class:`Scenario`, a dict, a built-in name or a YAML
    path. Everything ``tether validate`` checks happens here, before any
    simulation, and ``tether run`` calls this same function: the strategy's
    parameters, the ``sweep:`` block, the world, the initial team, whatever
    the strategy's ``initial_state`` / ``from_scenario`` check, and the memory
    the run would need.
    """
    scenario = as_scenario(scenario)
    seed = check_seed(seed)
    if seed is not None:  # the seed of the run is the scenario's, for every draw
        scenario = scenario.with_seed(seed)
    rng = np.random.default_rng(scenario.seed)
    cls = strategy_class(scenario)
    params = strategy_params(scenario, cls)
    check_link_range(scenario, params)
    check_sweep(scenario, cls)
    check_size_before_work(scenario)
    world = build_world(scenario, rng)
    sensor = make_sensor(scenario)
    initial = cls.initial_state(params, scenario, world, rng)
    pairs = None
    if initial is None:
        positions, pairs = _place_team(scenario, world, sensor, rng)
        initial = TeamState.at_rest(positions)
    strategy = cls.from_scenario(params, scenario, world, initial, rng)
    need = check_run_size(scenario, initial, strategy, sensor, pairs)
    return Built(scenario, world, sensor, initial, strategy, rng, need)


def check_link_range(scenario: Scenario, params: Any) -> None:
    """Refuse a sensing range below the range the strategy keeps links within (``rs_m``).

    The recorded graph is the sensed one (``sensing.range_m``); a strategy with ``rs_m``
    (the connectivity force's ``Rs``) keeps every link up to it. Below it, the force would
    count on links the robots cannot sense, and the recorded graph would not be the one
    the controller keeps connected.
    """
    rs = getattr(params, "rs_m", None)
    if isinstance(rs, int | float) and scenario.sensing.range_m < rs:
        preset = getattr(params, "preset", None)
        where = f" (preset {preset})" if preset else ""
        raise ScenarioError(
            f"{scenario.source}: sensing.range_m: {scenario.sensing.range_m:g} m is below the "
            f"strategy's link range Rs = {rs:g} m{where}: it would keep links the robots "
            f"cannot sense; set sensing.range_m: {rs:g} or lower strategy.params.rs_m"
        )


def place_team(
    scenario: Scenario, world: World, sensor: SensorModel, rng: np.random.Generator
) -> np.ndarray:
    """The team of ``team.init``: in free space and connected in the sensing graph."""
    return _place_team(scenario, world, sensor, rng)[0]


def _place_team(
    scenario: Scenario, world: World, sensor: SensorModel, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """Positions of ``team.init`` and their sensing pairs (without occlusion)."""
    try:
        positions = initial_positions(
            scenario.team.init, scenario.team.n_robots, world, rng, scenario.sensing.range_m
        )
    except ValueError as exc:
        head, sep, rest = str(exc).partition(": ")
        field = f"team.init.{head}" if sep and head in InitConfig.model_fields else "team.init"
        raise ScenarioError(
            f"{scenario.source}: {field}: {rest if field != 'team.init' else exc}"
        ) from None
    bad = ~world.points_free(positions)
    if bad.any():
        k = int(np.argmax(bad))
        raise ScenarioError(
            f"{scenario.source}: team.init: robot {k} at {positions[k].tolist()} is inside an "
            "obstacle or outside the world; move the team into free space"
        )
    # occlusion by robot bodies never changes whether the team is connected (see
    # tether.sensing.robots), so the check skips it: linear in the links, not their squares
    pairs = sensed_pairs(positions, replace(sensor, occlusion=False), world)
    if not is_connected(len(positions), pairs):
        raise ScenarioError(
            f"{scenario.source}: team.init: the initial team is not connected with "
            f"sensing.range_m={sensor.range_m}; place robots closer (spacing_m) or raise the range"
        )
    return positions, pairs


def default_run_dir(scenario: Scenario, seed: int, root: str | Path | None = None) -> Path:
    stamp = dt.datetime.now().strftime("%Y%m%d-%H%M%S-%f")
    return Path(root or scenario.output.dir) / f"{scenario.name}-s{seed}-{stamp}"


def run(
    scenario: Scenario | dict[str, Any] | str | Path,
    *,
    out_dir: str | Path | None = None,
    seed: int | None = None,
    figures: bool | None = None,
    progress: Callable[[int], None] | None = None,
    check: Callable[[], None] | None = None,
) -> RunOutcome:
    """Run one scenario and write its run folder; returns the folder and the summary.

    The folder is committed as a whole (:class:`tether.runfolder.RunFolder`):
    ``summary.json`` is written last, and the folder appears at ``out_dir``
    only when the run and its figures are complete. ``progress`` is called with
    each step number as the run goes (``tether run``'s progress bar). ``check`` is called
    after the scenario is built and before anything is written (the command line checks
    there what ``tether validate`` checks beyond :func:`build`, in the same order).
    """
    scenario = as_scenario(scenario)
    seed = check_seed(seed)
    if out_dir is not None and not isinstance(out_dir, str | Path):
        raise TypeError(f"out_dir must be a path (got {type(out_dir).__name__})")
    if figures is not None and not isinstance(figures, bool):
        raise TypeError(f"figures must be True, False or None (got {figures!r})")
    if seed is not None:  # the run folder records the seed it ran
        scenario = scenario.with_seed(seed)
    seed = scenario.seed
    built = build(scenario, seed)
    if check is not None:
        check()
    path = Path(out_dir) if out_dir is not None else default_run_dir(scenario, seed)
    folder = RunFolder(path)
    try:
        recorder = TrajectoryRecorder(every=scenario.output.record_every, on_step=progress)
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
    except BaseException:
        folder.abort()
        raise
    summary = write_run(folder, built, recorder, result, seed, wall, figures=figures)
    return RunOutcome(path, summary)


def write_run(
    folder: RunFolder,
    built: Built,
    recorder: TrajectoryRecorder,
    result: RunResult,
    seed: int,
    wall_time_s: float,
    *,
    figures: bool | None = None,
    extra: dict[str, Any] | None = None,
) -> dict[str, Any]:
    """Write a simulated run into ``folder`` and commit it; returns its summary.

    What :func:`run` writes after :func:`tether.sim.simulate`: the scenario, the tables of
    ``recorder``, the figures (``figures``: ``None`` follows ``output.figures``), then
    ``summary.json`` (:func:`tether.record.summarize`, plus ``extra`` keys) last. Any other
    loop that fills a :class:`TrajectoryRecorder` and a :class:`RunResult` the same way
    (an environment episode) writes its run folder through this function.
    """
    scenario = built.scenario
    path = folder.path
    try:
        data = scenario.model_dump(mode="json")
        kept = keep_scene_files(folder.staging, data, scene_files(scenario)[1])
        folder.write_yaml("scenario.yaml", data)
        folder.write_table("steps.parquet", recorder.step_columns())
        folder.write_table("robots.parquet", recorder.robot_columns())
        folder.write_table("links.parquet", recorder.link_columns())
        folder.write_rows("events.parquet", recorder.events)
        if scenario.output.figures if figures is None else figures:
            for name, fig in run_figures(built, recorder).items():
                folder.save_figure(fig, name)
        summary = summarize(scenario, seed, result, wall_time_s)
        if kept:  # the files the world read: their copies and hashes
            summary["scene_files"] = kept
        if extra:
            summary = {**summary, **extra}
        folder.commit(summary)
    except OSError as exc:  # the disk filled up, the folder was removed, ...
        folder.abort()
        raise OutputError(
            f"{path}: cannot write the run folder ({exc.strerror or exc}); choose another --out"
        ) from None
    except BaseException:
        folder.abort()
        raise
    return summary


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


__all__ = ["Built", "RunOutcome", "TetherError", "as_scenario", "build", "build_world",
           "check_seed", "run", "run_figures", "write_run"]  # fmt: skip
