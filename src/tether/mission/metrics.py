"""The metrics of an exploration mission, computed in one place for every paradigm.

From a :class:`~tether.mission.log.MissionLog` (one step = ``dt_s`` seconds; all
areas are shares of the *reachable* area, the free cells 8-connected to the base
station):

* ``base_time_to_{50,90,99}pct_s`` / ``team_time_to_...``: the first time the area
  known at the base station (BS) / sensed by any robot reaches 50, 90, 99 %
  (``None``: never in the run);
* ``base_explored_final`` / ``team_explored_final``: the shares at the end;
* ``path_length_m``: per robot, the length of its trajectory (sum of the step
  displacements); ``path_length_mean_m``;
* ``coverage_per_robot``: per robot, the share of the area it sensed itself;
  ``coverage_std``: their standard deviation over robots (population, ``ddof=0``);
* ``overlap_rate``: the share of the sensed area that two or more robots sensed;
* ``linked_to_base_frac``: per robot, the share of steps ``1..T`` in which it had
  a (multi-hop) link to the BS; ``linked_to_base_min``; ``all_linked_frac``: the
  share of steps in which every robot had one; ``team_connected_frac``: the share
  of steps in which the robots' own graph (without the BS) was connected;
* **information latency**, per cell a robot sensed: the delay between the first
  time any robot sensed it and the first time the BS knew it.
  ``latency_mean_s`` / ``latency_max_s`` over delivered cells,
  ``latency_undelivered_frac``: the share of sensed cells the BS never learnt in the
  run, and ``latency_quantiles_s``: the 0, 5, ..., 100 % quantiles over *all* sensed
  cells with an undelivered cell's latency infinite (a quantile that falls among
  them is ``None``), so paradigms that hold data back are not flattered.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from tether.mission.log import MissionLog

__all__ = [
    "LEVELS",
    "QUANTILES",
    "coverage_shares",
    "first_times",
    "latencies_steps",
    "mission_metrics",
    "overlap_rate",
    "path_lengths",
]

LEVELS = (0.5, 0.9, 0.99)
QUANTILES = tuple(np.linspace(0.0, 1.0, 21).round(2).tolist())


def first_times(series: np.ndarray, levels: tuple[float, ...] = LEVELS) -> list[int | None]:
    """The first index at which ``series >= level``, per level (``None``: never)."""
    s = np.asarray(series, dtype=float)
    out: list[int | None] = []
    for level in levels:
        hit = np.flatnonzero(s >= level - 1e-12)
        out.append(int(hit[0]) if len(hit) else None)
    return out


def path_lengths(positions: np.ndarray) -> np.ndarray:
    """``(n,)`` trajectory lengths of ``(T+1, n, d)`` positions."""
    p = np.asarray(positions, dtype=float)
    if len(p) < 2:
        return np.zeros(p.shape[1] if p.ndim == 3 else 0)
    return np.linalg.norm(np.diff(p, axis=0), axis=2).sum(axis=0)


def coverage_shares(robot_step: np.ndarray, reachable: np.ndarray) -> np.ndarray:
    """``(n,)`` share of the reachable cells each robot sensed itself."""
    reach = np.asarray(reachable, dtype=bool).reshape(-1)
    seen = (np.asarray(robot_step) >= 0) & reach[None, :]
    return seen.sum(axis=1) / max(int(reach.sum()), 1)


def overlap_rate(robot_step: np.ndarray, reachable: np.ndarray) -> float:
    """Share of the sensed reachable cells that two or more robots sensed (0 if none)."""
    reach = np.asarray(reachable, dtype=bool).reshape(-1)
    count = ((np.asarray(robot_step) >= 0) & reach[None, :]).sum(axis=0)
    sensed = int(np.count_nonzero(count >= 1))
    return float(np.count_nonzero(count >= 2) / sensed) if sensed else 0.0


def latencies_steps(
    robot_step: np.ndarray, base_step: np.ndarray, reachable: np.ndarray
) -> tuple[np.ndarray, int]:
    """Per sensed reachable cell, BS step minus first sensing step; and the undelivered count.

    Returns the latencies (steps) of the cells the BS learnt, and how many sensed
    cells it never learnt.
    """
    reach = np.asarray(reachable, dtype=bool).reshape(-1)
    rs = np.asarray(robot_step)
    seen_any = (rs >= 0).any(axis=0) & reach
    first = np.where(rs >= 0, rs, np.iinfo(np.int32).max).min(axis=0)
    base = np.asarray(base_step)
    delivered = seen_any & (base >= 0)
    lat = (base[delivered] - first[delivered]).astype(np.int64)
    if (lat < 0).any():
        raise ValueError("the base station knew a cell before any robot sensed it")
    return lat, int(np.count_nonzero(seen_any & (base < 0)))


def _quantiles(lat_s: np.ndarray, undelivered: int) -> list[float | None]:
    """Quantiles of the latencies with ``undelivered`` infinite values added."""
    total = len(lat_s) + undelivered
    if total == 0:
        return [None] * len(QUANTILES)
    ordered = np.sort(lat_s)
    out: list[float | None] = []
    for q in QUANTILES:
        k = int(np.ceil(q * total)) - 1 if q > 0 else 0  # the lower q-quantile (inverted CDF)
        out.append(float(ordered[k]) if k < len(ordered) else None)
    return out


def mission_metrics(log: MissionLog, dt_s: float) -> dict[str, Any]:
    """The summary keys of a mission (see the module docstring)."""
    out: dict[str, Any] = {}
    for who, series in (("base", log.base_explored), ("team", log.team_explored)):
        for level, k in zip(LEVELS, first_times(np.asarray(series)), strict=True):
            out[f"{who}_time_to_{round(100 * level)}pct_s"] = None if k is None else k * dt_s
        out[f"{who}_explored_final"] = float(series[-1]) if series else 0.0
    lengths = path_lengths(np.stack(log.positions_m))
    out["path_length_m"] = lengths.tolist()
    out["path_length_mean_m"] = float(lengths.mean()) if len(lengths) else 0.0
    shares = coverage_shares(log.robot_step, log.reachable)
    out["coverage_per_robot"] = shares.tolist()
    out["coverage_std"] = float(shares.std()) if len(shares) else 0.0
    out["overlap_rate"] = overlap_rate(log.robot_step, log.reachable)
    linked = np.asarray(log.linked[1:], dtype=bool).reshape(-1, log.n)
    per_robot = linked.mean(axis=0) if len(linked) else np.ones(log.n)
    out["linked_to_base_frac"] = per_robot.tolist()
    out["linked_to_base_min"] = float(per_robot.min()) if log.n else 1.0
    out["all_linked_frac"] = float(linked.all(axis=1).mean()) if len(linked) else 1.0
    team = np.asarray(log.team_connected[1:], dtype=bool)
    out["team_connected_frac"] = float(team.mean()) if len(team) else 1.0
    lat, undelivered = latencies_steps(log.robot_step, log.base_step, log.reachable)
    lat_s = lat * dt_s
    out["latency_mean_s"] = float(lat_s.mean()) if len(lat_s) else None
    out["latency_max_s"] = float(lat_s.max()) if len(lat_s) else None
    sensed = len(lat_s) + undelivered
    out["latency_undelivered_frac"] = undelivered / sensed if sensed else 0.0
    out["latency_quantiles_s"] = _quantiles(lat_s, undelivered)
    return out
