"""The targets a run recorded, read back from its events.

A strategy that sends robots to targets records each target as an event of kind
``target_added`` (``robot``, ``target`` id, ``position_m``; optionally
``stay_s``, ``appear_s``), and a target it is finished with as ``target_reached``
or ``target_dropped`` (``target`` id). The run folder's ``events.parquet`` then
holds every target actually used, whatever generated them (a fixed list, a random
draw, a schedule, a call from Python while the team ran), and the figures, the
animation, the replay and the export show them from there.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

#: event kinds of the target contract (see module docstring)
TARGET_ADDED = "target_added"
TARGET_FINISHED = ("target_reached", "target_dropped")


#: what :meth:`RecordedTargets.states` says of a target at an instant
HIDDEN, OPEN, FINISHED = 0, 1, 2


@dataclass(frozen=True)
class RecordedTargets:
    """Targets as arrays: ``positions_m`` ``(k, dim)``, their ids (``-1``: none given),
    the robot each was given to, the step it was added, the time it appears (s) and the
    step it was reached or dropped (``-1``: never)."""

    positions_m: np.ndarray
    ids: np.ndarray
    robots: np.ndarray
    added_steps: np.ndarray
    appear_s: np.ndarray
    finished_steps: np.ndarray

    def __len__(self) -> int:
        return len(self.positions_m)

    def states(self, step: int, t_s: float) -> np.ndarray:
        """``(k,)`` :data:`HIDDEN` (not added or not appeared yet), :data:`OPEN` or
        :data:`FINISHED` (reached or dropped by ``step``) at ``step``, time ``t_s``."""
        out = np.full(len(self), HIDDEN, dtype=np.int8)
        shown = (self.added_steps <= step) & (self.appear_s <= t_s + 1e-9)
        done = (self.finished_steps >= 0) & (self.finished_steps <= step)
        out[shown] = OPEN
        out[done] = FINISHED
        return out

    def first_frames(self, steps: np.ndarray, times_s: np.ndarray) -> np.ndarray:
        """``(k, 2)`` for frames at ``steps`` (increasing) and ``times_s``: the first frame
        where each target is shown and the first where it is finished (``-1``: none)."""
        steps = np.asarray(steps)
        times_s = np.asarray(times_s, dtype=float)
        shown = np.maximum(
            np.searchsorted(steps, self.added_steps, side="left"),
            np.searchsorted(times_s, self.appear_s - 1e-9, side="left"),
        )
        done = np.searchsorted(steps, self.finished_steps, side="left")
        done = np.where(self.finished_steps >= 0, done, len(steps))
        out = np.stack([shown, done], axis=1).astype(np.int64)
        out[out >= len(steps)] = -1
        return out


def _position(value: Any, dim: int) -> np.ndarray | None:
    """A recorded position as ``(dim,)`` floats (missing coordinates 0), else ``None``."""
    if isinstance(value, str):  # a column of mixed types is stored as JSON text
        import json

        try:
            value = json.loads(value)
        except ValueError:
            return None
    try:
        p = np.asarray(value, dtype=float).ravel()
    except (TypeError, ValueError):
        return None
    if not len(p) or not np.all(np.isfinite(p)):
        return None
    out = np.zeros(dim)
    out[: min(dim, len(p))] = p[:dim]
    return out


def _number(value: Any) -> float:
    """A recorded appearance time; missing or unreadable: 0 (there from the start)."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        return 0.0
    return v if np.isfinite(v) else 0.0


def recorded_targets(events: Iterable[Mapping[str, Any]], dim: int) -> RecordedTargets | None:
    """The targets in ``events`` (rows of ``events.parquet`` or a recorder's events).

    ``None`` when no ``target_added`` event holds a readable position.
    """
    pos: list[np.ndarray] = []
    robots: list[int] = []
    ids: list[int] = []
    added: list[int] = []
    appear: list[float] = []
    index: dict[Any, int] = {}
    finished: dict[Any, int] = {}
    for e in events:
        kind = e.get("kind")
        if kind == TARGET_ADDED:
            p = _position(e.get("position_m"), dim)
            if p is None:
                continue
            ident = e.get("target")
            if ident is not None:
                index[ident] = len(pos)
            ids.append(int(ident) if isinstance(ident, int | np.integer) else -1)
            pos.append(p)
            robots.append(int(e.get("robot", -1)))
            added.append(int(e.get("step", 0)))
            appear.append(_number(e.get("appear_s")))
        elif kind in TARGET_FINISHED and e.get("target") is not None:
            finished.setdefault(e["target"], int(e.get("step", 0)))
    if not pos:
        return None
    done = np.full(len(pos), -1, dtype=np.int64)
    for ident, step in finished.items():
        if ident in index:
            done[index[ident]] = step
    return RecordedTargets(
        np.vstack(pos),
        np.asarray(ids, dtype=np.int64),
        np.asarray(robots, dtype=np.int64),
        np.asarray(added, dtype=np.int64),
        np.asarray(appear, dtype=float),
        done,
    )
