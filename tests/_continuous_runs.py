"""Small ``connectivity`` and ``multi_target`` teams for the parameter-effect tests.

Both teams are four robots in a row 3 m apart (Table 2 outdoor: weighted lambda2 about
0.25, below ``lambda2_null`` = 1, so the connectivity force acts from the start). In
:data:`CONN` (free 2-D space) nothing pulls; :func:`pulled` adds constant forces that
pull the two end robots apart. In :data:`MT` (free 3-D space, straight paths) robot 3
has one target 40 m ahead, beyond the reach of a four-robot chain, so once it is the
prime traveler it stretches the team; before (the start-up election takes a few
control periods) every traveling force is zero.
"""

from __future__ import annotations

import copy
from typing import Any

import numpy as np

from _parameter_runs import Ran, built, ran
from tether.config import set_dotted

STRATEGIES = ("connectivity", "multi_target")

CONN: dict[str, Any] = {
    "name": "conn",
    "seed": 0,
    "world": {"scene": "free", "dim": 2},
    "team": {"n_robots": 4,
             "init": {"kind": "positions", "positions": [[0, 0], [3, 0], [6, 0], [9, 0]]}},
    "sensing": {"range_m": 10.0, "occlusion": False, "noise": "none"},
    "sim": {"dt_s": 0.1, "max_steps": 30},
    "strategy": {"name": "connectivity", "params": {}},
    "output": {"figures": False},
}  # fmt: skip

#: robot 3's one target, 40 m ahead of the row
FAR_TARGET = [49.0, 0.0, 5.0]

MT: dict[str, Any] = {
    "name": "mt",
    "seed": 0,
    "world": {"scene": "free", "dim": 3},
    "team": {"n_robots": 4, "init": {"kind": "positions",
                                     "positions": [[0, 0, 5], [3, 0, 5], [6, 0, 5], [9, 0, 5]]}},
    "sensing": {"range_m": 10.0, "occlusion": False, "noise": "none"},
    "sim": {"dt_s": 0.1, "max_steps": 30},
    "strategy": {"name": "multi_target", "params": {"targets": {"kind": "fixed", "params": {
        "queues": [{"robot": 3, "targets": [FAR_TARGET], "stay_s": 1.0}]}}}},
    "output": {"figures": False},
}  # fmt: skip

#: the end robots of CONN pulled apart (N), within ``magnitude_n``
PULL = {"kind": "constant", "forces": [[-3.0, 0.0], [0.0, 0.0], [0.0, 0.0], [3.0, 0.0]],
        "magnitude_n": 3.0}  # fmt: skip


def both(*keys: str) -> list[str]:
    """``connectivity:key`` and ``multi_target:key`` for each key."""
    return [f"{s}:{k}" for s in STRATEGIES for k in keys]


def scenario(strategy: str, **params: Any) -> dict[str, Any]:
    """The team of ``strategy`` with ``strategy.params`` set (dotted keys as ``a__b``)."""
    data = copy.deepcopy(CONN if strategy == "connectivity" else MT)
    for key, value in params.items():
        set_dotted(data["strategy"]["params"], key.replace("__", "."), value)
    return data


def pulled(strategy: str, **params: Any) -> dict[str, Any]:
    """The team stretched: CONN's ends pulled apart, MT's prime heading for its far target."""
    if strategy == "connectivity":
        params = {"external": PULL, **params}
    return scenario(strategy, **params)


def started(data: dict[str, Any]) -> tuple[Any, np.ndarray]:
    """The strategy built from ``data``, reset on its initial team (not stepped), and the
    team's positions."""
    b = built(data)
    b.strategy.reset(b.world, b.initial, b.rng)
    return b.strategy, b.initial.positions


def reset(data: dict[str, Any]) -> Any:
    """The strategy built from ``data`` and reset on its initial team (not stepped)."""
    return started(data)[0]


def run(data: dict[str, Any], steps: int | None = None) -> Ran:
    return ran(data, max_steps=steps)


def columns(r: Ran) -> dict[str, np.ndarray]:
    """The per-step columns of a run (``steps.parquet``'s), as arrays."""
    return {k: np.asarray(v) for k, v in r.recorder.step_columns().items()}


def moved_m(r: Ran) -> np.ndarray:
    """Each robot's distance from its start at the end of the run, ``(n,)``."""
    return np.linalg.norm(r.positions[-1] - r.positions[0], axis=1)
