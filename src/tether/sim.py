"""The one time loop of tether, and the plug-in contract every strategy follows.

One step of every simulation::

    state = strategy.step(ctx)                      # decide and move (the strategy's dynamics)
    obs   = strategy.sense(state, world, sensor)    # who is linked to whom after the move
    recorder.record(metrics(state, obs), ...)       # per-step records, values, events

Step 0 records the initial state. A strategy owns its motion model (a
kinematic step for the non-communicating strategy, the damped double
integrator of eq. (1) for the continuous one, robots following grid paths for
the exploration strategies), and may bring its own world model: the grid
exploration simulator of the recurrent-connectivity paper plugs in through the
``sense`` hook (its communication graph, with the base station as a fixed
node) and ``step_values`` / ``robot_values`` (explored area, who is connected),
so that the loop, the records, the summary and the run folder are the same for
every strategy.
"""

from __future__ import annotations

import os
import time
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from functools import cache
from types import ModuleType
from typing import Any, ClassVar, Protocol

import numpy as np
from pydantic import BaseModel, ConfigDict
from threadpoolctl import threadpool_limits

from tether import jit
from tether.graph import component_count, fiedler, pairs_within
from tether.graph.structure import KERNEL_PAIRS_MAX_N
from tether.interrupts import raise_if_stopped
from tether.sensing import Observation, SensorModel, sense
from tether.world.world import World

LAMBDA2_MAX_N = 500  # per-step lambda2 of the true graph is recorded up to this many nodes


def blas_threads() -> int:
    """BLAS threads while simulating: ``TETHER_BLAS_THREADS``, default 1.

    A team's matrices are tiny (35 x 35): with OpenBLAS threads a dense ``eigh``
    took 7.1 ms instead of 0.51 ms on this project's 2-core machine (under load),
    and sweeps run one trial per core anyway.
    """
    value = os.environ.get("TETHER_BLAS_THREADS", "1")
    return max(int(value), 1) if value.isdigit() else 1


@dataclass
class TeamState:
    """Team state as arrays: ``positions`` and ``velocities`` are ``(n, dim)``.

    ``fixed`` holds ``(k, dim)`` positions of fixed nodes of the team's graph
    (a base station); in an :class:`~tether.sensing.Observation` they are the
    nodes ``n .. n + k - 1`` after the robots.
    """

    positions: np.ndarray
    velocities: np.ndarray
    fixed: np.ndarray | None = None

    @classmethod
    def at_rest(cls, positions: np.ndarray, fixed: np.ndarray | None = None) -> TeamState:
        positions = np.array(positions, dtype=float)
        return cls(positions, np.zeros_like(positions), fixed)

    @property
    def n(self) -> int:
        return len(self.positions)

    @property
    def dim(self) -> int:
        return self.positions.shape[1]

    def copy(self) -> TeamState:
        fixed = None if self.fixed is None else self.fixed.copy()
        return TeamState(self.positions.copy(), self.velocities.copy(), fixed)


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


class NoParams(BaseModel):
    """The ``Params`` of a strategy without parameters (``strategy.params`` must be empty)."""

    model_config = ConfigDict(extra="forbid")


class Strategy(ABC):
    """The plug-in contract of a connectivity strategy.

    Required
        ``Params`` (a pydantic model of the scenario's ``strategy.params``),
        :meth:`from_scenario` and :meth:`step`.
    Optional (with defaults)
        :meth:`initial_state` (place the team yourself), :meth:`reset`,
        :meth:`sense` (your own interaction graph), :meth:`done`,
        :meth:`metrics` (summary keys), :meth:`step_values` /
        :meth:`robot_values` (extra per-step / per-robot columns),
        :meth:`figures` (extra PNGs for the run folder).

    Register a strategy with ``@STRATEGIES.register("name")``
    (:mod:`tether.registry`); ``tether run`` then runs it from YAML.
    """

    name: ClassVar[str] = "strategy"
    Params: ClassVar[type[BaseModel]] = NoParams

    def __init__(self) -> None:
        self._events: list[dict[str, Any]] = []
        self._step = 0

    # -- construction ------------------------------------------------------------------
    @classmethod
    def initial_state(
        cls, params: Any, scenario: Any, world: World, rng: np.random.Generator
    ) -> TeamState | None:
        """The team's initial state, or ``None`` to use the scenario's ``team.init``."""
        return None

    @classmethod
    @abstractmethod
    def from_scenario(
        cls,
        params: Any,
        scenario: Any,
        world: World,
        initial: TeamState,
        rng: np.random.Generator,
    ) -> Strategy:
        """Build the strategy from its validated ``params`` and the scenario.

        Raise :class:`tether.errors.ScenarioError` (one line: file, field, fix)
        for anything the scenario asks that cannot run.
        """

    # -- the loop ------------------------------------------------------------------------
    def reset(self, world: World, state: TeamState, rng: np.random.Generator) -> None:
        """Called once before the first step (and before step 0 is recorded)."""
        self._events.clear()
        self._step = 0

    @abstractmethod
    def step(self, ctx: StepContext) -> TeamState:
        """Move the team by one step of ``ctx.dt_s`` and return its new state."""

    def sense(
        self,
        state: TeamState,
        world: World,
        sensor: SensorModel | None,
        rng: np.random.Generator,
    ) -> Observation:
        """Who senses whom in ``state`` (default: :func:`tether.sensing.sense`)."""
        if sensor is None:
            raise ValueError(f"strategy {self.name!r} senses with a SensorModel; none given")
        return sense(state.positions, sensor, rng, world)

    def done(self) -> bool:
        """True ends the run early (e.g. the leader reached its goal)."""
        return False

    # -- results -------------------------------------------------------------------------
    def metrics(self) -> dict[str, Any]:
        """The strategy's own keys of ``summary.json`` (called once, after the run)."""
        return {}

    def step_values(self) -> dict[str, Any]:
        """Extra ``steps.parquet`` columns for the step just recorded (scalars)."""
        return {}

    def robot_values(self) -> dict[str, np.ndarray]:
        """Extra ``robots.parquet`` columns for the step just recorded, ``(n,)`` each."""
        return {}

    def figures(self, recording: Any, world: World, dt_s: float) -> dict[str, Any]:
        """Extra matplotlib figures ``{file name: figure}`` for ``figures/``.

        ``recording`` is the :class:`tether.record.TrajectoryRecorder` of the run.
        A name equal to a standard figure (``snapshot.png``) replaces it.
        """
        return {}

    # -- events --------------------------------------------------------------------------
    def emit(self, kind: str, robot: int = -1, **data: Any) -> None:
        """Record an event (role change, plan, election, ...) for ``events.parquet``."""
        self._events.append({"step": self._step, "kind": kind, "robot": int(robot), **data})

    def drain_events(self) -> list[dict[str, Any]]:
        out, self._events = self._events, []
        return out


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
    """Connectivity and safety metrics of the true interaction graph at one step.

    The graph has ``obs.n`` nodes: the robots, then any fixed nodes (a base
    station). Collisions count robot pairs closer than ``collision_distance_m``.
    Small teams (up to :data:`~tether.graph.structure.KERNEL_PAIRS_MAX_N` nodes), once
    numba is loaded (:func:`tether.jit.warm`), get all four numbers from one call of
    :func:`tether.graph.metrics_kernels.team_metrics_kernel`: the same values, except
    lambda2, which agrees with the reference's ``eigh`` to rounding (tests: 1e-12).
    """
    n = obs.n
    if n <= KERNEL_PAIRS_MAX_N and jit.warm() and positions.ndim == 2:
        return _team_metrics_compiled(step, t_s, positions, obs, collision_distance_m)
    n_comp, lam = _graph_metrics(n, obs.pairs)
    close = pairs_within(positions, collision_distance_m) if collision_distance_m > 0 else []
    if n > 1 and len(obs.pairs):
        d = np.linalg.norm(obs.true_relative, axis=1).min()
    else:
        d = float("inf")
    return StepRecord(step, t_s, n_comp <= 1, n_comp, len(obs.pairs), lam, float(d), len(close))


@cache
def _metrics_kernels() -> ModuleType:
    """:mod:`tether.graph.metrics_kernels`, imported on first use (it loads numba)."""
    from tether.graph import metrics_kernels

    return metrics_kernels


def _team_metrics_compiled(
    step: int, t_s: float, positions: np.ndarray, obs: Observation, collision_distance_m: float
) -> StepRecord:
    """:func:`team_metrics` in one compiled call (the graph's part skipped on a cache hit)."""
    n = obs.n
    pairs = np.ascontiguousarray(obs.pairs, dtype=np.int64).reshape(-1, 2)
    key = ("compiled", n, pairs.shape, pairs.tobytes())
    hit = _GRAPH_CACHE["key"] == key
    n_comp, lam, d, close = _metrics_kernels().team_metrics_kernel(
        n, pairs, np.ascontiguousarray(positions, dtype=float),
        np.ascontiguousarray(obs.true_relative, dtype=float), float(collision_distance_m),
        not hit,
    )  # fmt: skip
    if hit:
        n_comp, lam = _GRAPH_CACHE["value"]
    else:
        _GRAPH_CACHE["key"], _GRAPH_CACHE["value"] = key, (n_comp, lam)
    return StepRecord(step, t_s, n_comp <= 1, n_comp, len(pairs), lam, d, close)


#: the last graph's metrics: a team's sensing graph often stays the same for many steps
_GRAPH_CACHE: dict[str, Any] = {"key": None, "value": None}


def _graph_metrics(n: int, pairs: np.ndarray) -> tuple[int, float]:
    """Components and lambda2 of the unweighted graph, reused while the graph is unchanged.

    Both depend only on ``n`` and the links, so an unchanged graph (same links in the
    same order) gets exactly the values computed for it before.
    """
    pairs = np.ascontiguousarray(pairs)
    key = (n, pairs.shape, pairs.dtype.str, pairs.tobytes())
    if _GRAPH_CACHE["key"] == key:
        return _GRAPH_CACHE["value"]
    n_comp = component_count(n, pairs)
    lam = float("nan")
    if n <= LAMBDA2_MAX_N:  # full dense eigh up to 400 nodes: the recorded values since 0.1
        lap = None
        if jit.warm() and n <= 400:  # the same matrix, compiled
            from tether.graph.kernels import laplacian_dense_kernel

            lap = laplacian_dense_kernel(n, pairs.astype(np.int64), np.ones(len(pairs)))
        lam = fiedler(n, pairs, method="dense" if n <= 400 else "sparse", laplacian=lap)[0]
    _GRAPH_CACHE["key"], _GRAPH_CACHE["value"] = key, (n_comp, lam)
    return n_comp, lam


@dataclass
class RunResult:
    """What a finished simulation returns (the recorder holds the full history)."""

    steps: int
    sim_time_s: float
    wall_time_s: float
    records: list[StepRecord]
    final_state: TeamState
    strategy_metrics: dict[str, Any] = field(default_factory=dict)
    cpu_time_s: float = float("nan")

    @property
    def connected_all_steps(self) -> bool:
        return all(r.connected for r in self.records)


class Recorder(Protocol):
    """Receives every step: team metrics, state, observation, events and extra values."""

    def record(
        self,
        rec: StepRecord,
        state: TeamState,
        obs: Observation,
        events: list[dict[str, Any]],
        values: dict[str, Any],
        robot_values: dict[str, np.ndarray],
    ) -> None: ...


def simulate(
    world: World,
    sensor: SensorModel | None,
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
    ``sensor`` may be ``None`` for strategies that bring their own ``sense``.
    """
    if not isinstance(rng, np.random.Generator):
        raise TypeError("rng must be a numpy.random.Generator, e.g. np.random.default_rng(0)")
    if not (np.isfinite(dt_s) and dt_s > 0):
        raise ValueError(f"dt_s must be a positive finite number (got {dt_s!r})")
    if int(max_steps) != max_steps or max_steps < 0:
        raise ValueError(f"max_steps must be a non-negative integer (got {max_steps!r})")
    with threadpool_limits(limits=blas_threads(), user_api="blas"):
        return _loop(world, sensor, strategy, initial, dt_s, max_steps, rng,
                     collision_distance_m, recorder)  # fmt: skip


def _loop(
    world: World,
    sensor: SensorModel | None,
    strategy: Strategy,
    initial: TeamState,
    dt_s: float,
    max_steps: int,
    rng: np.random.Generator,
    collision_distance_m: float,
    recorder: Recorder | None,
) -> RunResult:
    start, cpu_start = time.perf_counter(), time.process_time()
    state = initial.copy()
    strategy.reset(world, state, rng)
    records: list[StepRecord] = []
    obs = strategy.sense(state, world, sensor, rng)
    step = 0
    while True:
        raise_if_stopped()  # a Ctrl-C that a weak-reference callback swallowed
        rec = team_metrics(step, step * dt_s, state.positions, obs, collision_distance_m)
        records.append(rec)
        if recorder is not None:
            recorder.record(
                rec,
                state,
                obs,
                strategy.drain_events(),
                strategy.step_values(),
                strategy.robot_values(),
            )
        if step >= max_steps or strategy.done():
            break
        ctx = StepContext(step, step * dt_s, dt_s, world, state, obs, rng)
        state = strategy.step(ctx)
        step += 1
        obs = strategy.sense(state, world, sensor, rng)
    return RunResult(
        steps=step,
        sim_time_s=step * dt_s,
        wall_time_s=time.perf_counter() - start,
        cpu_time_s=time.process_time() - cpu_start,
        records=records,
        final_state=state,
        strategy_metrics=strategy.metrics(),
    )
