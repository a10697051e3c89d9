"""Who knows what: robots' local maps and the global map at the base station.

Recurrent-connectivity paper (Banfi et al., Sec. III and VII): robots keep
local grid maps of what they sensed; the base station (BS) keeps a global map
that learns only what *connected* robots transmit; data gathered while
disconnected is flushed to the BS on reconnection. Robots that can exchange
data (same component of the communication graph) share their maps.

Sensing is noise-free and the world static, so an observed cell's occupancy is
always the true one; a map is therefore just a boolean ``known`` mask and the
occupancy of a known cell is read from the true grid. This keeps merging a map
to one ``|=`` per robot.
"""

from __future__ import annotations

import numpy as np

__all__ = ["Knowledge"]


class Knowledge:
    """Known-cell masks of ``n`` robots and of the BS.

    Parameters
    ----------
    shape
        Grid shape ``(nx, ny)``.
    n_robots
        Team size.
    """

    def __init__(self, shape: tuple[int, int], n_robots: int) -> None:
        self.shape = tuple(shape)
        self.n = int(n_robots)
        self.global_known = np.zeros(self.shape, dtype=bool)
        self.local_known = np.zeros((self.n, *self.shape), dtype=bool)
        self.dirty = np.zeros(self.n, dtype=bool)  # new cells since last exchange
        self._last_group: list[frozenset[int]] = [frozenset()] * self.n
        self.global_version = 0  # bumped whenever the BS map grows
        self._seen = np.full(self.n, -1, dtype=np.int64)  # BS version each robot holds

    def observe(self, robot: int, flat_cells: np.ndarray) -> None:
        """Robot ``robot`` senses the cells ``flat_cells`` (flat indices)."""
        if len(flat_cells):
            flat = self.local_known[robot].reshape(-1)
            if not flat[flat_cells].all():
                flat[flat_cells] = True
                self.dirty[robot] = True

    def exchange(self, groups: list[list[int]], with_bs: list[bool]) -> None:
        """Merge maps inside each communication group.

        ``groups[k]`` are robot ids able to exchange data; ``with_bs[k]`` says
        whether the BS is in that group, in which case everything the group
        knows is flushed to the BS and the BS map is shared back. Groups whose
        members, data and BS map did not change since the last call are skipped.
        """
        for members, bs in zip(groups, with_bs, strict=True):
            if not members:
                continue
            key = frozenset(members) | ({-1} if bs else frozenset())
            stale = any(self._last_group[r] != key for r in members)
            behind = bs and any(self._seen[r] != self.global_version for r in members)
            if not (stale or behind or self.dirty[members].any()):
                continue
            union = np.logical_or.reduce(self.local_known[members], axis=0)
            if bs:
                grown = union & ~self.global_known
                if grown.any():
                    self.global_known |= grown
                    self.global_version += 1
                union = self.global_known
            for r in members:
                self.local_known[r] |= union
                self._last_group[r] = key
                if bs:
                    self._seen[r] = self.global_version
            self.dirty[members] = False
