"""The shared time loop and the ``Strategy`` protocol.

One step of every simulation::

    obs   = sense(world, positions)          # who senses whom, noisy relative positions
    state = strategy.step(ctx)               # the strategy moves the team (its own dynamics)
    recorder.record(step, state, obs)        # per-step records, metrics, events

A strategy owns its motion model (a kinematic step for the non-communicating
strategy, the damped double integrator for the continuous one), built from the
shared functions in :mod:`tether.dynamics`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Protocol, runtime_checkable

import numpy as np

from tether.graph import algebraic_connectivity, components, pairs_within
from tether.sensing import Observation, SensorModel, sense
from tether.world.world import World

LAMBDA2_MAX_N = 500  # per-step lambda2 of the true graph is recorded up to this team size


@dataclass
class TeamState:
    """Team state as arrays: ``positions`` and ``velocities`` are ``(n, dim)``."""

    positions: np.ndarray
    velocities: np.ndarray

    @classmethod
    def at_rest(cls, positions: np.ndarray) -> TeamState:
        positions = np.array(positions, dtype=float)
        return cls(positions, np.zeros_like(positions))

    @property
    def n(self) -> int:
        return len(self.positions)

    @property
    def dim(self) -> int:
        return self.positions.shape[1]

    def copy(self) -> TeamState:
        return TeamState(self.positions.copy(), self.velocities.copy())


@dataclass
class StepContext:
    """Everything a strategy may use to compute one step."""

    step: int
    t_s: float
    dt_s: float
    world: World
    state: TeamState
    obs: Observation
    rng: np.random.Generator


@runtime_checkable
class Strategy(Protocol):
    """What the simulator needs from a connectivity strategy."""

    name: str

    def reset(self, world: World, state: TeamState, rng: np.random.Generator) -> None: ...

    def step(self, ctx: StepContext) -> TeamState: ...

    def done(self) -> bool: ...

    def metrics(self) -> dict[str, Any]: ...

    def drain_events(self) -> list[dict[str, Any]]: ...


class StrategyBase:
    """Convenience base: event buffer, never done, no extra metrics."""

    name = "base"

    def __init__(self) -> None:
        self._events: list[dict[str, Any]] = []
        self._step = 0

    def reset(self, world: World, state: TeamState, rng: np.random.Generator) -> None:
        self._events.clear()

    def emit(self, kind: str, robot: int = -1, **data: Any) -> None:
        """Record an event (role change, plan, election, ...) for the run folder."""
        self._events.append({"step": self._step, "kind": kind, "robot": int(robot), **data})

    def drain_events(self) -> list[dict[str, Any]]:
        out, self._events = self._events, []
        return out

    def done(self) -> bool:
        return False

    def metrics(self) -> dict[str, Any]:
        return {}


@dataclass
class StepRecord:
    """Team-level metrics of one step (the true interaction graph)."""

    step: int
    t_s: float
    connected: bool
    n_components: int
    n_links: int
    lambda2: float
    min_distance_m: float
    collisions: int


def team_metrics(
    step: int, t_s: float, positions: np.ndarray, obs: Observation, collision_distance_m: float
) -> StepRecord:
    """Connectivity and safety metrics of the true interaction graph at one step."""
    n = len(positions)
    n_comp, _ = components(n, obs.pairs)
    lam = float("nan")
    if n <= LAMBDA2_MAX_N:  # full dense eigh up to 400 robots: the recorded values since 0.1
        lam = algebraic_connectivity(n, obs.pairs, method="dense" if n <= 400 else "sparse")
    close = pairs_within(positions, collision_distance_m) if collision_distance_m > 0 else []
    if n > 1 and len(obs.pairs):
        d = np.linalg.norm(obs.true_relative, axis=1).min()
    else:
        d = float("inf")
    return StepRecord(step, t_s, n_comp <= 1, n_comp, len(obs.pairs), lam, float(d), len(close))


@dataclass
class RunResult:
    """What a finished simulation returns (the recorder holds the full history)."""

    steps: int
    sim_time_s: float
    wall_time_s: float
    records: list[StepRecord]
    final_state: TeamState
    strategy_metrics: dict[str, Any] = field(default_factory=dict)

    @property
    def connected_all_steps(self) -> bool:
        return all(r.connected for r in self.records)


class Recorder(Protocol):
    def record(
        self, rec: StepRecord, state: TeamState, obs: Observation, events: list[dict]
    ) -> None: ...


def simulate(
    world: World,
    sensor: SensorModel,
    strategy: Strategy,
    initial: TeamState,
    *,
    dt_s: float,
    max_steps: int,
    rng: np.random.Generator,
    collision_distance_m: float = 0.0,
    recorder: Recorder | None = None,
) -> RunResult:
    """Run ``strategy`` from ``initial`` until it is done or ``max_steps`` have passed.

    Step 0 records the initial state; every later step records the state after
    the strategy has moved. The run is fully determined by the inputs and ``rng``.
    """
    start = time.perf_counter()
    state = initial.copy()
    strategy.reset(world, state, rng)
    records: list[StepRecord] = []
    obs = sense(state.positions, sensor, rng, world)
    step = 0
    while True:
        rec = team_metrics(step, step * dt_s, state.positions, obs, collision_distance_m)
        records.append(rec)
        if recorder is not None:
            recorder.record(rec, state, obs, strategy.drain_events())
        if step >= max_steps or strategy.done():
            break
        ctx = StepContext(step, step * dt_s, dt_s, world, state, obs, rng)
        state = strategy.step(ctx)
        step += 1
        obs = sense(state.positions, sensor, rng, world)
    return RunResult(
        steps=step,
        sim_time_s=step * dt_s,
        wall_time_s=time.perf_counter() - start,
        records=records,
        final_state=state,
        strategy_metrics=strategy.metrics(),
    )
