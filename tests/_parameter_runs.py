"""Small runs for the parameter-effect tests: a scenario dict, changed, built and run."""

from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Any

import numpy as np

from tether.config import scenario_from_dict, set_dotted
from tether.record import TrajectoryRecorder
from tether.runner import Built, build
from tether.sim import RunResult, simulate

SILENT: dict[str, Any] = {
    "name": "effects",
    "seed": 1,
    "world": {"scene": "free", "dim": 2},
    "team": {"n_robots": 6, "init": {"kind": "grid", "spacing_m": 6.0}},
    "sensing": {"range_m": 15.0},
    "sim": {"dt_s": 1.0, "max_steps": 10},
    "strategy": {
        "name": "silent",
        "params": {
            "d0_m": 8.0,
            "gamma": 0.2,
            "trajectory": {"kind": "waypoints", "waypoints": [[0, 0], [60, 0]]},
        },
    },
    "output": {"figures": False},
}


@dataclass
class Ran:
    built: Built
    result: RunResult
    recorder: TrajectoryRecorder

    @property
    def positions(self) -> np.ndarray:
        """``(recorded steps, n, dim)``."""
        return np.stack(self.recorder.positions)

    @property
    def metrics(self) -> dict[str, Any]:
        return self.result.strategy_metrics


def changed(base: dict[str, Any], **overrides: Any) -> dict[str, Any]:
    """A deep copy of ``base`` with dotted keys set (``sim__dt_s=2`` sets ``sim.dt_s``)."""
    data = copy.deepcopy(base)
    for key, value in overrides.items():
        set_dotted(data, key.replace("__", "."), value)
    return data


def built(data: dict[str, Any]) -> Built:
    return build(scenario_from_dict(data))


def ran(data: dict[str, Any], max_steps: int | None = None) -> Ran:
    """Build and simulate ``data`` (no run folder)."""
    b = built(data)
    sc = b.scenario
    recorder = TrajectoryRecorder(every=sc.output.record_every)
    result = simulate(
        b.world,
        b.sensor,
        b.strategy,
        b.initial,
        dt_s=sc.sim.dt_s,
        max_steps=max_steps or sc.sim.max_steps,
        rng=b.rng,
        collision_distance_m=sc.sim.collision_distance_m,
        recorder=recorder,
    )
    return Ran(b, result, recorder)
