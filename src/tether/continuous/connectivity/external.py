"""The external force ``f_i`` of the ``connectivity`` strategy (eq. (1)), always bounded.

Fact 1 of the continuous-connectivity paper holds while ``f_i`` stays bounded: every kind
here is saturated at ``magnitude_n`` per robot. ``none``; ``constant`` (``forces``: one
vector for all robots or one per robot); ``goal`` (operator commands: ``robots`` are
pulled towards ``goals`` by ``gain * (goal - q)``, saturated); ``random`` (each robot a
uniformly random direction and a magnitude uniform in ``[0, magnitude_n]``, redrawn every
``hold_s``; ``planar`` keeps them horizontal in 3-D).
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from tether.errors import ScenarioError
from tether.sim import TeamState


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


class ExternalForce(_Strict):
    """The external force ``f_i`` of eq. (1), bounded by ``magnitude_n`` per robot.

    ``none``; ``constant`` (``forces``: one vector for all robots or one per
    robot); ``goal`` (operator commands: ``robots`` are pulled towards
    ``goals`` by ``gain * (goal - q)``, saturated); ``random`` (each robot a
    uniformly random direction and a magnitude uniform in
    ``[0, magnitude_n]``, redrawn every ``hold_s``; ``planar`` keeps them
    horizontal in 3-D).
    """

    kind: Literal["none", "constant", "goal", "random"] = "none"
    magnitude_n: float = Field(default=1.0, ge=0)
    hold_s: float = Field(default=2.0, gt=0)
    planar: bool = False
    forces: list[list[float]] | None = None
    robots: list[int] = Field(default_factory=list)
    goals: list[list[float]] = Field(default_factory=list)
    gain_n_per_m: float = Field(default=1.0, ge=0)


def external_force(
    spec: ExternalForce, q: np.ndarray, rng: np.random.Generator, held: np.ndarray | None
) -> np.ndarray:
    """``f_i`` per robot, ``(n, dim)``, never longer than ``spec.magnitude_n``."""
    n, dim = q.shape
    if spec.kind == "none":
        return np.zeros((n, dim))
    if spec.kind == "constant":
        f = np.broadcast_to(np.asarray(spec.forces or [[0.0] * dim], dtype=float), (n, dim))
    elif spec.kind == "goal":
        f = np.zeros((n, dim))
        for robot, goal in zip(spec.robots, spec.goals, strict=True):
            f[robot] = spec.gain_n_per_m * (np.asarray(goal, dtype=float) - q[robot])
    else:
        if held is not None:
            return held
        direction = rng.normal(size=(n, dim))
        if spec.planar and dim == 3:
            direction[:, 2] = 0.0
        direction /= np.maximum(np.linalg.norm(direction, axis=1, keepdims=True), 1e-12)
        f = direction * rng.uniform(0.0, spec.magnitude_n, size=(n, 1))
    norm = np.linalg.norm(f, axis=1, keepdims=True)
    return f * np.minimum(1.0, spec.magnitude_n / np.maximum(norm, 1e-300))


def check_external(
    ext: ExternalForce, failures: dict[int, int], initial: TeamState, src: str
) -> None:
    """Robot indices and vector sizes of the external force and failures fit the team."""
    n, dim = initial.n, initial.dim
    field = f"{src}: strategy.params.external"
    bad = [r for r in ext.robots if not 0 <= r < n]
    if bad:
        raise ScenarioError(f"{field}.robots: {bad[0]} is not a robot index in 0..{n - 1}")
    if ext.kind == "goal" and len(ext.goals) != len(ext.robots):
        raise ScenarioError(
            f"{field}.goals: {len(ext.goals)} goals for {len(ext.robots)} robots; give one "
            "goal per robot"
        )
    if any(len(g) != dim for g in ext.goals):
        raise ScenarioError(f"{field}.goals: each goal needs {dim} coordinates")
    if ext.forces is not None and (
        len(ext.forces) not in (1, n) or any(len(f) != dim for f in ext.forces)
    ):
        raise ScenarioError(
            f"{field}.forces: give one force of {dim} numbers for all robots or one per robot ({n})"
        )
    check_failures(failures, n, src)


def check_failures(failures: dict[int, int], n: int, src: str) -> None:
    """The robots of ``estimator.failures`` are robots of the team of ``n``."""
    bad = [r for r in failures if not 0 <= r < n]
    if bad:
        raise ScenarioError(
            f"{src}: strategy.params.estimator.failures: {bad[0]} is not a robot index in "
            f"0..{n - 1}"
        )
