"""What a run records, and the one summary every run gets.

:class:`TrajectoryRecorder` keeps the per-step history of
:func:`tether.sim.simulate` in memory and turns it into the columns of the run
folder's tables::

    steps.parquet     one row per step: team metrics of the true graph, plus the
                      strategy's step values (e.g. explored_fraction)
    robots.parquet    one row per (recorded step, robot): x_m, y_m[, z_m], plus the
                      strategy's robot values (e.g. connected)
    links.parquet     one row per (recorded step, link): i, j (indices >= n_robots
                      are fixed nodes such as a base station)
    events.parquet    one row per event (role changes, plans, elections, ...)

:func:`summarize` computes the core keys of ``summary.json`` for every strategy.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import fields
from typing import Any

import numpy as np

from tether.errors import ScenarioError
from tether.limits import format_bytes, memory_budget_bytes
from tether.runfolder import provenance
from tether.sensing import Observation, SensorModel
from tether.sim import RunResult, StepRecord, Strategy, TeamState

#: summary keys every run has; a strategy metric with one of these names gets a prefix
CORE_KEYS = ("scenario", "strategy", "seed", "n_robots", "dim", "sim_time_s", "steps",
             "wall_time_s", "cpu_time_s")  # fmt: skip


class TrajectoryRecorder:
    """Collects per-step records of a :func:`tether.sim.simulate` run in memory.

    ``every`` keeps robot positions and links only every k-th step (team
    metrics and step values are kept at every step); ``keep_positions=False``
    drops them altogether (large teams). ``on_step`` is called with each step
    number once it is recorded (a progress bar).
    """

    def __init__(
        self,
        every: int = 1,
        keep_positions: bool = True,
        on_step: Callable[[int], None] | None = None,
    ) -> None:
        self.every = max(int(every), 1)
        self.keep_positions = keep_positions
        self.on_step = on_step
        self.steps: list[StepRecord] = []
        self.values: list[dict[str, Any]] = []
        self.position_steps: list[int] = []
        self.positions: list[np.ndarray] = []
        self.links: list[np.ndarray] = []
        self.robot_values: list[dict[str, np.ndarray]] = []
        self.events: list[dict[str, Any]] = []
        self.fixed: np.ndarray | None = None

    def record(
        self,
        rec: StepRecord,
        state: TeamState,
        obs: Observation,
        events: list[dict[str, Any]],
        values: dict[str, Any] | None = None,
        robot_values: dict[str, np.ndarray] | None = None,
    ) -> None:
        self.steps.append(rec)
        self.values.append(dict(values or {}))
        self.events.extend(events)
        if state.fixed is not None and self.fixed is None:
            self.fixed = np.asarray(state.fixed, dtype=float).copy()
        if self.keep_positions and rec.step % self.every == 0:
            self.position_steps.append(rec.step)
            self.positions.append(state.positions.copy())
            self.links.append(obs.pairs.copy())
            self.robot_values.append({k: np.asarray(v).copy() for k, v in
                                      (robot_values or {}).items()})  # fmt: skip
        if self.on_step is not None:
            self.on_step(rec.step)

    def nodes(self, k: int) -> np.ndarray:
        """Positions of every graph node at the ``k``-th recorded step (robots, then fixed)."""
        if self.fixed is None:
            return self.positions[k]
        return np.vstack([self.positions[k], self.fixed])

    def step_columns(self) -> dict[str, list[Any]]:
        names = [f.name for f in fields(StepRecord)]  # scalars: no deep copy (asdict's)
        rows = [{k: getattr(r, k) for k in names} | v
                for r, v in zip(self.steps, self.values, strict=True)]  # fmt: skip
        keys = list(dict.fromkeys(k for r in rows for k in r))
        return {k: [r.get(k) for r in rows] for k in keys}

    def robot_columns(self) -> dict[str, np.ndarray]:
        if not self.positions:
            return {"step": np.empty(0, int), "robot": np.empty(0, int)}
        pos = np.stack(self.positions)  # (T, n, dim)
        t, n, dim = pos.shape
        cols: dict[str, np.ndarray] = {
            "step": np.repeat(np.asarray(self.position_steps), n),
            "robot": np.tile(np.arange(n), t),
        }
        for d, axis in zip(range(dim), "xyz", strict=False):
            cols[f"{axis}_m"] = pos[:, :, d].ravel()
        for key in self.robot_values[0]:
            cols[key] = np.concatenate([rv[key] for rv in self.robot_values])
        return cols

    def link_columns(self) -> dict[str, np.ndarray]:
        if not self.links:
            return {"step": np.empty(0, int), "i": np.empty(0, int), "j": np.empty(0, int)}
        steps = np.concatenate(
            [np.full(len(lk), s) for s, lk in zip(self.position_steps, self.links, strict=True)]
        )
        both = np.concatenate(self.links).reshape(-1, 2)
        return {"step": steps.astype(int), "i": both[:, 0], "j": both[:, 1]}


def summarize(scenario: Any, seed: int, result: RunResult, wall_time_s: float) -> dict[str, Any]:
    """The ``summary.json`` of a run: the core keys (README), then the strategy's metrics.

    Core keys, the same for every strategy: ``scenario``, ``strategy``,
    ``seed``, ``n_robots``, ``dim``, ``sim_time_s``, ``steps``,
    ``wall_time_s``, ``cpu_time_s`` (the simulation's processor time),
    ``connected_all_steps`` (the true interaction graph,
    fixed nodes included, connected at every step), ``min_lambda2``
    (unweighted), ``min_links``, ``max_links``, ``collisions``,
    ``collision_distance_m``, ``min_distance_m`` and ``provenance``. A
    strategy metric that reuses a core name is stored as ``strategy_<name>``.
    """
    recs = result.records
    lam = np.array([r.lambda2 for r in recs], dtype=float)
    core = {
        "scenario": scenario.name,
        "strategy": scenario.strategy.name,
        "seed": seed,
        "n_robots": scenario.team.n_robots,
        "dim": scenario.world.dim,
        "sim_time_s": result.sim_time_s,
        "steps": result.steps,
        "wall_time_s": wall_time_s,
        "cpu_time_s": result.cpu_time_s,
        "connected_all_steps": result.connected_all_steps,
        "min_lambda2": float(np.nanmin(lam)) if np.isfinite(lam).any() else None,
        "min_links": int(min(r.n_links for r in recs)),
        "max_links": int(max(r.n_links for r in recs)),
        "collisions": int(sum(r.collisions for r in recs)),
        "collision_distance_m": scenario.sim.collision_distance_m,
        "min_distance_m": float(min(r.min_distance_m for r in recs)),
    }
    reserved = set(CORE_KEYS) | {"provenance"}
    own = {f"strategy_{k}" if k in reserved else k: v for k, v in result.strategy_metrics.items()}
    return {**core, **own, "provenance": provenance()}


# --------------------------------------------------------------------------- memory


def record_bytes(steps: int, recorded: int, n: int, dim: int, links: int) -> float:
    """Bytes the recorder keeps: per-step records, positions and links of recorded steps."""
    records = steps * 400.0  # a StepRecord and its values per step
    records += recorded * n * (dim + 2) * 8 * 2  # positions, then their table columns
    records += recorded * links * 2 * 8 * 2  # link pairs, then their table columns
    return records


def check_size_before_work(scenario: Any) -> float:
    """Refuse, before the world is built or a robot placed, a run that cannot fit in memory.

    The estimate is a lower bound: the team's positions while it is placed, and what the
    recorder keeps with the fewest links a connected team can have (``n - 1``). A run that
    passes is checked again with its real links once the team is placed
    (:func:`check_run_size`). Returns the lower bound in bytes.
    """
    n, dim = scenario.team.n_robots, scenario.world.dim
    steps = scenario.sim.max_steps + 1
    recorded = scenario.sim.max_steps // scenario.output.record_every + 1
    placement = n * dim * 8 * 8.0  # positions, candidates, a k-d tree of them
    need = record_bytes(steps, recorded, n, dim, max(n - 1, 0)) + placement
    budget = memory_budget_bytes()
    if need > budget:
        raise ScenarioError(
            f"{scenario.source}: team.n_robots: {n:,} robots over {scenario.sim.max_steps:,} "
            f"steps need at least {format_bytes(need)} (their positions and links at every "
            f"recorded step), more than the {format_bytes(budget)} allowed here; use fewer "
            "robots or steps, raise output.record_every, or set TETHER_MEMORY_LIMIT_GB"
        )
    return need


def check_run_size(
    scenario: Any,
    initial: TeamState,
    strategy: Strategy,
    sensor: SensorModel,
    pairs: np.ndarray | None,
) -> float:
    """Refuse a run whose records or per-step sensing would not fit in memory; the estimate.

    The estimate counts what the recorder keeps (per-step records; positions
    and links of every recorded step, links counted as in the initial team)
    and, for strategies on the core sensing model with occlusion, the
    per-step occlusion test (``sum of degree^2`` candidate triples).
    """
    n = initial.n + (0 if initial.fixed is None else len(initial.fixed))
    steps = scenario.sim.max_steps + 1
    recorded = scenario.sim.max_steps // scenario.output.record_every + 1
    links = 0 if pairs is None else len(pairs)
    records = record_bytes(steps, recorded, n, initial.dim, links)
    occlusion = 0.0
    core_sensing = type(strategy).sense is Strategy.sense
    if core_sensing and links and sensor.occlusion and sensor.body_radius_m > 0:
        degree = np.bincount(pairs.ravel(), minlength=initial.n).astype(float)
        occlusion = float(degree @ degree) * 150  # the arrays of one step's occlusion test
    need, budget = records + occlusion, memory_budget_bytes()
    if need <= budget:
        return need
    what = f"{initial.n:,} robots with {links:,} links at the start"
    if occlusion > records:
        raise ScenarioError(
            f"{scenario.source}: team.n_robots: {what}: testing which robot bodies hide which "
            f"links needs about {format_bytes(occlusion)} at every step, more than the "
            f"{format_bytes(budget)} allowed here; use fewer robots, a shorter sensing.range_m, "
            "or sensing.occlusion: false"
        )
    raise ScenarioError(
        f"{scenario.source}: team.n_robots: {what}: recording {scenario.sim.max_steps:,} steps "
        f"needs about {format_bytes(need)}, more than the {format_bytes(budget)} allowed here; "
        "use fewer robots or steps, or raise output.record_every"
    )
