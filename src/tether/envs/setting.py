"""A scenario seen as an environment: its kind, its robots' speed bound, links and task.

The scenario is built exactly as ``tether run`` builds it (:func:`tether.runner.build`:
the same world, initial team, targets and random stream for a seed); this module reads
off what an environment needs:

========================  ============  ==========================================  ==========
strategy                  kind          speed bound (action 1.0)                    task
========================  ============  ==========================================  ==========
``silent``                leader        ``max_speed_mps``, else ``sensing.range_m /  LeaderPath
                                        sim.dt_s`` (constraints (1)-(2) keep every
                                        step of the paper's robots below it)
``connectivity``          continuous    the robot model's ``max_speed_mps``         Goals / none
``multi_target``          targets       the robot model's ``max_speed_mps``         Targets
``recurrent``, ``utility`` exploration  ``speed_m_s``                               Coverage
anything else             free          the ``max_speed_mps`` option (required)     none
========================  ============  ==========================================  ==========

Links are the scenario's sensing graph (range, line of sight, occlusion by robot bodies,
as ``tether run`` records it); exploration kinds link robots and the base station within
the strategy's ``comm_range_m`` with a clear line of sight, as their runs do.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from tether.envs.options import EnvOptions
from tether.envs.tasks import Coverage, Goals, LeaderPath, NoTask, Targets
from tether.runner import Built
from tether.sensing import SensorModel

KINDS = {
    "silent": "leader",
    "connectivity": "continuous",
    "multi_target": "targets",
    "recurrent": "exploration",
    "utility": "exploration",
}

#: kinds whose strategy runs as a scripted policy on the environment
SCRIPTED_KINDS = ("leader", "continuous", "targets")


@dataclass
class Setting:
    """What an environment needs of one built scenario."""

    kind: str
    n: int
    dim: int
    dt_s: float
    max_steps: int
    max_speed_mps: float
    link_sensor: SensorModel
    link_range_m: float
    collision_distance_m: float
    clearance_m: float
    fixed: np.ndarray | None

    @property
    def step_m(self) -> float:
        """How far an action of norm 1 moves a robot in one step."""
        return self.max_speed_mps * self.dt_s


def kind_of(built: Built) -> str:
    return KINDS.get(built.scenario.strategy.name, "free")


def _speed(built: Built, kind: str, options: EnvOptions) -> float:
    scenario, strategy = built.scenario, built.strategy
    if options.max_speed_mps is not None:
        return options.max_speed_mps
    if kind == "leader":
        own = getattr(strategy, "max_speed_mps", None)
        if own is not None:
            return float(own)
        return max(scenario.sensing.range_m / scenario.sim.dt_s, strategy.speed_mps)
    if kind in ("continuous", "targets"):
        bound = float(strategy.integ.robot.max_speed_mps)
        if not np.isfinite(bound) or bound > 1e4:
            raise ValueError(
                f"{scenario.source}: strategy.params.max_speed_mps: {bound:g} m/s is not a "
                "speed bound an action can scale; set it (or the max_speed_mps option)"
            )
        return bound
    if kind == "exploration":
        return float(scenario.strategy.params.get("speed_m_s", 0.4))
    raise ValueError(
        f"{scenario.source}: strategy {scenario.strategy.name!r} has no speed bound the "
        "environment knows; pass the max_speed_mps option"
    )


def make_setting(built: Built, options: EnvOptions) -> Setting:
    """The :class:`Setting` of ``built`` under ``options``."""
    scenario = built.scenario
    kind = kind_of(built)
    sensor = built.sensor
    link_range = sensor.range_m
    if kind == "exploration":
        link_range = float(scenario.strategy.params.get("comm_range_m", 15.0))
        sensor = SensorModel(link_range, occlusion=False, noise="none")
    elif kind in ("continuous", "targets"):
        link_range = float(built.strategy.conn.rs_m)
    collision = scenario.sim.collision_distance_m
    clearance = options.clearance_m if options.clearance_m is not None else collision / 2
    fixed = built.initial.fixed
    return Setting(
        kind,
        built.initial.n,
        built.initial.dim,
        scenario.sim.dt_s,
        scenario.sim.max_steps,
        _speed(built, kind, options),
        sensor,
        link_range,
        collision,
        clearance,
        None if fixed is None else fixed.copy(),
    )


def make_task(built: Built, setting: Setting, options: EnvOptions) -> NoTask:
    """The task of ``built`` (call after the strategy's ``reset``: the leader is chosen there)."""
    strategy, scenario = built.strategy, built.scenario
    if setting.kind == "leader":
        return LeaderPath(
            strategy.leader,
            strategy.trajectory,
            strategy.speed_mps,
            setting.dt_s,
            2 * strategy.d_max_m,
            strategy.goal_tolerance_m,
        )
    if setting.kind == "continuous":
        ext = strategy.params.external
        if ext.kind == "goal" and ext.robots:
            return Goals(ext.robots, np.asarray(ext.goals, dtype=float))
        return NoTask()
    if setting.kind == "targets":
        queues = [
            [(t.position_m.copy(), t.stay_s, t.appear_s) for t in queue]
            for queue in strategy.targets.queues
        ]
        return Targets(queues, strategy.params.rz_m, setting.dt_s)
    if setting.kind == "exploration" and setting.fixed is not None:
        cell = options.coverage_cell_m or scenario.sensing.range_m / 5
        return Coverage(built.world, scenario.sensing.range_m, cell, setting.fixed[0])
    return NoTask()


def sensor_without_noise(sensor: SensorModel) -> SensorModel:
    return replace(sensor, noise="none")
