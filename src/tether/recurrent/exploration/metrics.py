"""What researchers measure in an exploration run, step by step.

:class:`MissionMetrics` is fed once per step by the adapter
(:mod:`tether.recurrent.exploration.run`) and gives the summary keys:

* ``time_to_50pct_s``, ``time_to_75pct_s``, ``time_to_90pct_s``: the first time
  (seconds, ``step * dt_s``) at which the area known *at the BS* reaches 50, 75,
  90 % of the free area reachable from the BS; ``None`` if never reached.
* ``time_moving_frac``, ``time_relaying_frac``, ``time_waiting_frac``,
  ``time_returning_frac``: the share of robot time in each state of
  :class:`RobotState` over all steps ``1..T`` and all robots that have not failed
  (a failed robot's steps count in none of them, so the four sum to 1).
* ``out_of_comm_episodes``, ``out_of_comm_longest_steps``,
  ``out_of_comm_episode_mean_steps``: maximal runs of consecutive steps in which a
  live robot had no multi-hop link to the BS, counted over all robots; an episode
  still open at the end of the run counts (with its length so far); a robot that
  fails ends its episode.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["MissionMetrics", "RobotState", "classify", "episodes", "first_reach"]

THRESHOLDS = (0.5, 0.75, 0.9)


class RobotState:
    """Where a robot's time goes in one step (exclusive; checked in this order).

    ``RETURNING``
        Heading back to the BS on its own (the Utility baseline's return rule,
        and a robot cut off by a failed relay), whether or not it advanced.
    ``MOVING``
        Advanced along its path in this step.
    ``RELAYING``
        Stood still at its goal while that goal lies on the relay path ``P_f`` of
        a frontier ``f`` (Sec. VI) whose data has not reached the BS yet, ``f``
        being another robot's goal: it is held there as a relay.
    ``WAITING``
        Anything else: standing still before moving (a planning delay), at its
        goal not ready (for its own frontier's data or its chain), ready and
        waiting for a plan, or idle with nothing left to explore.
    ``FAILED``
        Failed (not counted in the shares).
    """

    MOVING = 0
    RELAYING = 1
    WAITING = 2
    RETURNING = 3
    FAILED = 4
    NAMES = ("moving", "relaying", "waiting", "returning", "failed")


def classify(
    moved: np.ndarray, returning: np.ndarray, relaying: np.ndarray, alive: np.ndarray
) -> np.ndarray:
    """The :class:`RobotState` of every robot in one step (int array)."""
    moved, returning = np.asarray(moved, bool), np.asarray(returning, bool)
    relaying, alive = np.asarray(relaying, bool), np.asarray(alive, bool)
    out = np.full(len(moved), RobotState.WAITING, dtype=np.int8)
    out[relaying] = RobotState.RELAYING
    out[moved] = RobotState.MOVING
    out[returning] = RobotState.RETURNING
    out[~alive] = RobotState.FAILED
    return out


def episodes(out_of_comm: np.ndarray) -> list[int]:
    """Lengths of the maximal runs of ``True`` in a boolean ``(T,)`` series."""
    x = np.r_[False, np.asarray(out_of_comm, bool), False].astype(np.int8)
    d = np.diff(x)
    starts, ends = np.flatnonzero(d == 1), np.flatnonzero(d == -1)
    return (ends - starts).tolist()


def first_reach(series: np.ndarray, level: float) -> int | None:
    """First index at which ``series >= level`` (``None`` if never)."""
    hit = np.flatnonzero(np.asarray(series, float) >= level - 1e-12)
    return int(hit[0]) if len(hit) else None


class MissionMetrics:
    """Accumulates the per-step quantities of one run (see the module docstring)."""

    def __init__(self, n: int, explored0: float) -> None:
        self.n = n
        self.explored = [float(explored0)]
        self.counts = np.zeros(len(RobotState.NAMES), dtype=np.int64)
        self.out: list[np.ndarray] = []  # (n,) out of communication and alive, per step

    def add(self, explored: float, states: np.ndarray, connected: np.ndarray) -> None:
        """Record one step: explored fraction at the BS, robot states, who is connected."""
        self.explored.append(float(explored))
        self.counts += np.bincount(states, minlength=len(RobotState.NAMES))
        alive = states != RobotState.FAILED
        self.out.append(~np.asarray(connected, bool) & alive)

    def summary(self, dt_s: float) -> dict[str, Any]:
        out: dict[str, Any] = {}
        for level in THRESHOLDS:
            k = first_reach(np.asarray(self.explored), level)
            out[f"time_to_{round(100 * level)}pct_s"] = None if k is None else k * dt_s
        live = int(self.counts[: RobotState.FAILED].sum())
        for code, name in enumerate(RobotState.NAMES[: RobotState.FAILED]):
            out[f"time_{name}_frac"] = float(self.counts[code] / live) if live else 0.0
        series = np.array(self.out).reshape(-1, self.n)
        lengths = [le for r in range(self.n) for le in episodes(series[:, r])]
        out["out_of_comm_episodes"] = len(lengths)
        out["out_of_comm_longest_steps"] = int(max(lengths, default=0))
        out["out_of_comm_episode_mean_steps"] = float(np.mean(lengths)) if lengths else 0.0
        return out
