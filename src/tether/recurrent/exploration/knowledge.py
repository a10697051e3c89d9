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

A group that is the same as at its members' last exchange (and, with the BS, whose
members hold the BS map's current version) shares one map plus what each member
sensed since; the exchange then only writes the cells that were new to their
observers (``incremental``), instead of merging whole maps; a changed group merges
one map per group its members last exchanged in (plus what the others sensed since)
instead of every member's. Both give the same maps (tests compare them).
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
    incremental
        Exchange only the newly sensed cells inside unchanged groups (the same maps
        as merging whole maps, the reference with ``False``).
    """

    def __init__(self, shape: tuple[int, int], n_robots: int, incremental: bool = True) -> None:
        self.shape = tuple(shape)
        self.n = int(n_robots)
        self.incremental = bool(incremental)
        # cells each robot learnt by sensing since its last exchange (new to it)
        self._pending: list[list[np.ndarray]] = [[] for _ in range(self.n)]
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
            seen = flat[flat_cells]
            if not seen.all():
                new = flat_cells[~seen]
                flat[new] = True
                self._pending[robot].append(new)
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
            if self.incremental and not (stale or behind):
                self._exchange_new(members, bs)
                continue
            if self.incremental:
                union = self._union(members)
            else:
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
                self._pending[r].clear()
            self.dirty[members] = False

    def _union(self, members: list[int]) -> np.ndarray:
        """The union of the members' maps, one map per group they last exchanged in.

        Robots that last exchanged in the same group left it with equal maps (and
        robots that never exchanged all started from an empty one); since then each
        added only its ``_pending`` cells. So the union is that of one member's map per
        such group, plus the cells the others sensed since.
        """
        first: dict[frozenset[int], int] = {}
        for r in members:
            first.setdefault(self._last_group[r], r)
        reps = list(first.values())
        union = np.logical_or.reduce(self.local_known[reps], axis=0)
        taken = set(reps)
        rest = [c for r in members if r not in taken for c in self._pending[r]]
        if rest:
            union.reshape(-1)[np.concatenate(rest)] = True
        return union

    def _exchange_new(self, members: list[int], bs: bool) -> None:
        """The exchange of an unchanged group: only the cells sensed since the last one.

        At their last exchange (this group) the members' maps were made equal (to the
        BS map, with the BS, which has not grown since: no member is behind); since
        then each added only the cells in its ``_pending`` list. So the union of their
        maps is the shared map plus those cells, and the merge writes just them.
        """
        new = [c for r in members for c in self._pending[r]]
        cells = np.concatenate(new) if new else np.empty(0, dtype=np.intp)
        if bs:
            flat = self.global_known.reshape(-1)
            if not flat[cells].all():
                flat[cells] = True
                self.global_version += 1
        for r in members:
            self.local_known[r].reshape(-1)[cells] = True
            if bs:
                self._seen[r] = self.global_version
            self._pending[r].clear()
        self.dirty[members] = False
