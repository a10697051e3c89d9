"""The message layer: robots talk only to their current neighbours.

Every decentralized algorithm (consensus, eigenvector estimation, floods)
exchanges data through :class:`MessageLayer`, so faults are injected in one
place:

* **neighbours only** -- a message from ``j`` reaches ``i`` only over a link
  ``(i, j)`` of the graph given for that round;
* **loss** -- each directed message is dropped independently with
  probability ``loss_probability``;
* **delay** -- a message sent in round ``r`` arrives in round
  ``r + delay_rounds`` (if its link still exists then; a mailbox is
  emptied when its link disappears);
* **failure** -- a failed robot neither sends nor receives from its failure
  round on (``failures = {robot: round}``).

Each robot keeps, per neighbour, the last value it received (a mailbox), so
with loss or delay a receiver works with stale values; :meth:`exchange`
returns them per directed link together with their age in rounds.

All randomness comes from the generator passed in, so runs are reproducible.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

import numpy as np

from tether import jit

_NONE = np.zeros(0)  # no loss draws


@dataclass(frozen=True)
class CommParams:
    """Fault model of the message layer (defaults: perfect, instantaneous links)."""

    loss_probability: float = 0.0
    delay_rounds: int = 0
    failures: dict[int, int] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if not 0.0 <= self.loss_probability < 1.0:
            raise ValueError("loss_probability must be in [0, 1)")
        if self.delay_rounds < 0:
            raise ValueError("delay_rounds must be >= 0")


@dataclass
class Inbox:
    """What every robot holds after a round, per directed link ``receiver <- sender``.

    ``receiver``/``sender`` are ``(e,)`` arrays over the current links (both
    directions), ``values`` the ``(e, k)`` last received values (``nan``
    where nothing was ever received) and ``age`` the rounds since sending
    (``-1`` where nothing was received).
    """

    receiver: np.ndarray
    sender: np.ndarray
    values: np.ndarray
    age: np.ndarray

    @property
    def valid(self) -> np.ndarray:
        return self.age >= 0


def directed(pairs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Both directions of undirected ``pairs``: ``(receiver, sender)``."""
    pairs = np.asarray(pairs, dtype=np.intp).reshape(-1, 2)
    return np.concatenate([pairs[:, 0], pairs[:, 1]]), np.concatenate([pairs[:, 1], pairs[:, 0]])


def smallest_per_receiver(receiver: np.ndarray, *keys: np.ndarray) -> np.ndarray:
    """Row index, per receiver that has rows, of its row with the smallest ``keys``.

    Keys compare lexicographically, the first most significant; ties go to the
    earlier row. Receivers come out in increasing order. A robot picking the best
    message in its inbox (an election's candidate, a flood's nearest sender) uses it.
    """
    order = np.lexsort((*reversed(keys), receiver))
    r = receiver[order]
    first = np.ones(len(order), dtype=bool)
    first[1:] = r[1:] != r[:-1]
    return order[first]


class MessageLayer:
    """Synchronous rounds of neighbour-to-neighbour broadcasts with faults.

    Parameters
    ----------
    n
        Number of robots.
    params
        Loss, delay and failures.
    rng
        Source of the loss draws.
    """

    def __init__(self, n: int, params: CommParams, rng: np.random.Generator) -> None:
        self.n = n
        self.params = params
        self.rng = rng
        self.round = 0
        self._in_flight: deque[tuple[np.ndarray, np.ndarray, int]] = deque()
        # mailbox aligned with the current directed links (codes receiver * n + sender)
        self._codes = np.empty(0, dtype=np.int64)
        self._order = np.empty(0, dtype=np.intp)
        self._vals = np.empty((0, 0))
        self._sent_at = np.empty(0, dtype=np.int64)
        self._dead_from = np.full(n, np.iinfo(np.int64).max)
        for robot, at in params.failures.items():
            if 0 <= robot < n:
                self._dead_from[robot] = at
        self.sent = 0
        self.delivered = 0
        # links of the last exchange, reused while the caller passes the same array
        self._last_pairs: np.ndarray | None = None
        self._last_links: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None

    def alive(self, round_: int | None = None) -> np.ndarray:
        """Boolean ``(n,)``: robots that have not failed by ``round_`` (default: now)."""
        return (self.round if round_ is None else round_) < self._dead_from

    @property
    def perfect(self) -> bool:
        """No loss, no delay and no failure: every message arrives fresh every round."""
        p = self.params
        failing = any(0 <= robot < self.n for robot in p.failures)
        return p.loss_probability == 0 and p.delay_rounds == 0 and not failing

    def perfect_rounds(self, pairs: np.ndarray, rounds: int) -> None:
        """Account for ``rounds`` rounds over ``pairs`` on a :attr:`perfect` layer.

        On a perfect layer every robot holds its neighbours' current values
        after each round, so a caller may compute a round directly from the
        senders' values (e.g. as a Laplacian product) instead of calling
        :meth:`exchange`; this keeps the round counter and the message counts
        as if it had. The mailboxes are emptied: the next :meth:`exchange`
        refills all of them (nothing is lost on a perfect layer).
        """
        if not self.perfect:
            raise ValueError("perfect_rounds needs a layer without loss, delay or failures")
        messages = 2 * len(np.asarray(pairs).reshape(-1, 2)) * rounds
        self.sent += messages
        self.delivered += messages
        self.round += rounds
        self._last_pairs = None
        self._codes = np.empty(0, dtype=np.int64)
        self._order = np.empty(0, dtype=np.intp)
        self._vals = np.empty((0, 0))
        self._sent_at = np.empty(0, dtype=np.int64)

    def _slots(self, codes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Mailbox slots of ``codes`` among the current links, and whether each exists."""
        if len(self._codes) == 0:
            return np.zeros(len(codes), dtype=np.intp), np.zeros(len(codes), dtype=bool)
        pos = np.minimum(np.searchsorted(self._codes, codes, sorter=self._order),
                         len(self._codes) - 1)  # fmt: skip
        slot = self._order[pos]
        return slot, self._codes[slot] == codes

    def _relink(self, codes: np.ndarray, k: int) -> None:
        """Re-align the mailboxes with a new link set (mail over vanished links is dropped)."""
        if self._vals.shape[1] == k and jit.enabled():  # the same mailboxes, compiled
            from tether.comm_kernels import relink_kernel

            self._vals, self._sent_at = relink_kernel(self._codes, self._vals, self._sent_at,
                                                      codes, self.n)  # fmt: skip
            self._codes, self._order = codes, np.argsort(codes, kind="stable")
            return
        vals = np.full((len(codes), k), np.nan)
        sent_at = np.full(len(codes), -1, dtype=np.int64)
        if self._vals.shape[1] == k:
            slot, found = self._slots(codes)
            vals[found] = self._vals[slot[found]]
            sent_at[found] = self._sent_at[slot[found]]
        self._codes, self._order = codes, np.argsort(codes, kind="stable")
        self._vals, self._sent_at = vals, sent_at

    def exchange(self, pairs: np.ndarray, values: np.ndarray) -> Inbox:
        """One round: every alive robot broadcasts its row of ``values`` to its neighbours.

        Parameters
        ----------
        pairs
            ``(m, 2)`` current undirected links. Passing the same array object
            again reuses the previous round's link bookkeeping, so it must not
            be modified in place between rounds.
        values
            ``(n, k)`` what each robot sends this round.
        """
        values = np.asarray(values, dtype=float).reshape(self.n, -1)
        k = values.shape[1]
        if pairs is self._last_pairs and self._vals.shape[1] == k:
            recv, send, codes = self._last_links  # the same link array as last round
        else:
            recv, send = directed(pairs)
            codes = recv.astype(np.int64) * self.n + send
            if self._vals.shape[1] != k or not np.array_equal(codes, self._codes):
                self._relink(codes, k)
            self._last_pairs, self._last_links = pairs, (recv, send, codes)
        if self.params.delay_rounds == 0 and jit.enabled():  # the same round, compiled
            from tether.comm_kernels import deliver_kernel

            draws = self.rng.random(len(recv)) if self.params.loss_probability > 0 else _NONE
            sent, delivered, age = deliver_kernel(
                self._vals, self._sent_at, values, recv, send, self._dead_from, draws,
                self.params.loss_probability, self.round,
            )  # fmt: skip
            self.sent += sent
            self.delivered += delivered
            self.round += 1
            return Inbox(recv, send, self._vals, age)
        alive = self.alive()
        ok = alive[recv] & alive[send]
        self.sent += int(ok.sum())
        if self.params.loss_probability > 0:
            ok &= self.rng.random(len(recv)) >= self.params.loss_probability
        if self.params.delay_rounds == 0:
            self._vals[ok] = values[send[ok]]
            self._sent_at[ok] = self.round
            self.delivered += int(ok.sum())
        else:
            self._in_flight.append((codes[ok], values[send[ok]], self.round))
            if len(self._in_flight) > self.params.delay_rounds:
                code_d, vals_d, sent_d = self._in_flight.popleft()
                slot, found = self._slots(code_d)
                # deliver only over links that exist now, to receivers alive now
                found &= alive[code_d // self.n]
                newer = found.copy()
                newer[found] = self._sent_at[slot[found]] < sent_d
                self._vals[slot[newer]] = vals_d[newer]
                self._sent_at[slot[newer]] = sent_d
                self.delivered += int(found.sum())
        age = np.where(self._sent_at >= 0, self.round - self._sent_at, -1)
        self.round += 1
        return Inbox(recv, send, self._vals, age)

    @property
    def delivery_ratio(self) -> float:
        """Delivered / sent messages so far (1.0 before any message)."""
        return self.delivered / self.sent if self.sent else 1.0
