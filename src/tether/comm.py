"""The message layer: robots talk only to their current neighbours.

Every decentralized algorithm (consensus, eigenvector estimation, floods)
exchanges data through :class:`MessageLayer`, so faults are injected in one
place:

* **neighbours only** -- a message from ``j`` reaches ``i`` only over a link
  ``(i, j)`` of the graph given for that round;
* **loss** -- each directed message is dropped independently with
  probability ``loss_probability``;
* **delay** -- a message sent in round ``r`` arrives in round
  ``r + delay_rounds`` (if its link still exists then);
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
        self._in_flight: deque[tuple[np.ndarray, np.ndarray, np.ndarray]] = deque()
        self._box_code = np.empty(0, dtype=np.int64)
        self._box_vals = np.empty((0, 0))
        self._box_sent = np.empty(0, dtype=np.int64)
        self.sent = 0
        self.delivered = 0

    def alive(self, round_: int | None = None) -> np.ndarray:
        """Boolean ``(n,)``: robots that have not failed by ``round_`` (default: now)."""
        r = self.round if round_ is None else round_
        ok = np.ones(self.n, dtype=bool)
        for robot, at in self.params.failures.items():
            if 0 <= robot < self.n and r >= at:
                ok[robot] = False
        return ok

    def exchange(self, pairs: np.ndarray, values: np.ndarray) -> Inbox:
        """One round: every alive robot broadcasts its row of ``values`` to its neighbours.

        Parameters
        ----------
        pairs
            ``(m, 2)`` current undirected links.
        values
            ``(n, k)`` what each robot sends this round.
        """
        values = np.asarray(values, dtype=float).reshape(self.n, -1)
        k = values.shape[1]
        if self._box_vals.shape[1] != k:
            self._box_vals = np.empty((0, k))
        recv, send = directed(pairs)
        alive = self.alive()
        ok = alive[recv] & alive[send]
        if self.params.loss_probability > 0:
            ok &= self.rng.random(len(recv)) >= self.params.loss_probability
        self.sent += int((alive[recv] & alive[send]).sum())
        code = recv[ok].astype(np.int64) * self.n + send[ok]
        self._in_flight.append((code, values[send[ok]], np.full(len(code), self.round)))
        codes_now = recv.astype(np.int64) * self.n + send
        if len(self._in_flight) > self.params.delay_rounds:
            code_d, vals_d, sent_d = self._in_flight.popleft()
            # deliver only over links that exist now, to receivers that are alive now
            arrive = np.isin(code_d, codes_now) & alive[code_d // self.n]
            self.delivered += int(arrive.sum())
            self._store(code_d[arrive], vals_d[arrive], sent_d[arrive])
        out_vals = np.full((len(recv), k), np.nan)
        age = np.full(len(recv), -1, dtype=np.int64)
        if len(self._box_code):
            pos = np.searchsorted(self._box_code, codes_now)
            pos = np.minimum(pos, len(self._box_code) - 1)
            hit = self._box_code[pos] == codes_now
            out_vals[hit] = self._box_vals[pos[hit]]
            age[hit] = self.round - self._box_sent[pos[hit]]
        self.round += 1
        return Inbox(recv, send, out_vals, age)

    def _store(self, code: np.ndarray, vals: np.ndarray, sent: np.ndarray) -> None:
        """Merge delivered messages into the mailboxes (newer replaces older)."""
        all_code = np.concatenate([self._box_code, code])
        all_vals = np.concatenate([self._box_vals, vals])
        all_sent = np.concatenate([self._box_sent, sent])
        order = np.lexsort((-all_sent, all_code))
        all_code = all_code[order]
        first = np.r_[True, all_code[1:] != all_code[:-1]]
        self._box_code = all_code[first]
        self._box_vals = all_vals[order][first]
        self._box_sent = all_sent[order][first]

    @property
    def delivery_ratio(self) -> float:
        """Delivered / sent messages so far (1.0 before any message)."""
        return self.delivered / self.sent if self.sent else 1.0
