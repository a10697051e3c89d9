"""What an exploration mission records step by step, for :mod:`tether.mission.metrics`.

A mission explores a 2-D occupancy grid from a base station (BS). Whatever the
paradigm, the same four things happen every step and :class:`MissionLog` keeps them:

* each robot senses cells (flat indices into the grid): the first step robot ``r``
  sensed cell ``c`` is ``robot_step[r, c]`` (``-1``: never);
* the BS map grows: the first step the BS knew cell ``c`` is ``base_step[c]``;
* robots move: their positions in metres, one ``(n, 2)`` array per step;
* links: whether each robot has a (multi-hop) link to the BS, and whether the
  robots' own graph (without the BS) is connected.

Only cells of the *reachable* area (free cells 8-connected to the BS) count in
the explored fractions; the per-cell arrays keep every cell so that the metrics
can restrict to that area in one place.
"""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

__all__ = ["MissionLog"]


class MissionLog:
    """Per-step record of a mission.

    Parameters
    ----------
    reachable
        Boolean grid ``(nx, ny)``: the free area reachable from the BS.
    n_robots
        Team size.
    """

    def __init__(self, reachable: np.ndarray, n_robots: int) -> None:
        self.reachable = np.asarray(reachable, dtype=bool).reshape(-1)
        self.n = int(n_robots)
        cells = self.reachable.size
        self.robot_step = np.full((self.n, cells), -1, dtype=np.int32)
        self.base_step = np.full(cells, -1, dtype=np.int32)
        self._team = np.zeros(cells, dtype=bool)
        self._team_count = 0
        self._base_count = 0
        self._base_version: object = None
        self.team_explored: list[float] = []
        self.base_explored: list[float] = []
        self.positions_m: list[np.ndarray] = []
        self.linked: list[np.ndarray] = []
        self.team_connected: list[bool] = []

    @property
    def reachable_cells(self) -> int:
        return int(self.reachable.sum())

    @property
    def steps(self) -> int:
        """Steps recorded after step 0."""
        return len(self.positions_m) - 1

    def record(
        self,
        step: int,
        sensed: Iterable[tuple[int, np.ndarray]],
        base_known: np.ndarray,
        positions_m: np.ndarray,
        linked: np.ndarray,
        team_connected: bool,
        base_version: object = None,
    ) -> None:
        """Record step ``step`` (``0, 1, 2, ...`` in order).

        Parameters
        ----------
        sensed
            ``(robot, flat cell indices)`` for every scan of this step.
        base_known
            The BS's known mask after this step's communication.
        positions_m
            ``(n, 2)`` robot positions.
        linked
            ``(n,)`` robot linked to the BS (multi-hop).
        team_connected
            The robots' communication graph (without the BS) is connected.
        base_version
            A token that changes whenever ``base_known`` grows (skips an unchanged map).
        """
        if step != len(self.positions_m):
            raise ValueError(f"steps must be recorded in order (expected {len(self.positions_m)})")
        for robot, cells in sensed:
            cells = np.asarray(cells, dtype=np.intp)
            row = self.robot_step[robot]
            new = np.unique(cells[row[cells] < 0])  # a scan may name a cell twice
            row[new] = step
            fresh = new[~self._team[new]]
            self._team[fresh] = True
            self._team_count += int(np.count_nonzero(self.reachable[fresh]))
        if base_version is None or base_version != self._base_version:
            self._base_version = base_version
            known = np.asarray(base_known, dtype=bool).reshape(-1)
            new = np.flatnonzero(known & (self.base_step < 0))
            self.base_step[new] = step
            self._base_count += int(np.count_nonzero(self.reachable[new]))
        total = max(self.reachable_cells, 1)
        self.team_explored.append(self._team_count / total)
        self.base_explored.append(self._base_count / total)
        self.positions_m.append(np.asarray(positions_m, dtype=float).copy())
        self.linked.append(np.asarray(linked, dtype=bool).copy())
        self.team_connected.append(bool(team_connected))
