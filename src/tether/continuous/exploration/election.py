"""The prime-traveler election by flooding over the message layer (Sec. 3.3).

The host of an election (robot 0 at start-up, then the prime traveler when it
reaches its target) opens election ``e``; the candidates (secondary travelers;
at start-up every robot with a target) flood ``(criterion, index)`` and every
robot keeps the smallest pair it heard (ties to the lower index). After
``2(N - 1)`` rounds (``2(N - 1)(1 + d)`` when messages arrive ``d`` rounds late: the
round trip to a candidate ``N - 1`` hops away) the host decides: the best candidate it
heard wins, and the
result is flooded until it reaches the winner, who becomes the prime traveler.
Every message goes through :class:`tether.comm.MessageLayer`, so loss, delay and
failures reach the election too: a lost reply can only make a worse candidate
win, never two primes.

**At most one prime traveler.** The right to be prime is a single token: it
starts with the host of the start-up election and moves only from a host to the
winner of the host's own election. A winner that is no longer a secondary
traveler when the result reaches it (it reached its target meanwhile) floods a
*decline* and the token stays with the host, who opens a new election. A host
whose election found no candidate keeps the token idle and polls again. This
departs from Algorithm 1 in one place: a connector that receives a target when
no prime exists becomes a secondary traveler and is elected, instead of making
itself prime (line 8), because "no prime in the group" cannot be known exactly
under delays, and two connectors acting on it at once would make two primes. The
one robot that does know is the token holder: after the start-up election, a holder
that is a secondary traveler itself (a prime whose succession found no candidate,
then took its next target) ends its poll as the winner at once (line 8 exactly), so
no prime role stays vacant while its only candidate waits for its own poll.

The state is arrays over robots; a round updates robot ``i`` from its own row
and its inbox only.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from tether import jit
from tether.comm import MessageLayer, smallest_per_receiver

# message fields (columns)
EPOCH, HOST, BEST, BEST_IDX, RESULT, WINNER, ACK, ACK_CODE = range(8)
TAKEN, DECLINED = 1.0, 2.0

#: the merge's groups: the field compared, then the fields adopted with it (-1 pads)
_GROUPS = np.array([[EPOCH, EPOCH, HOST, BEST, BEST_IDX], [RESULT, RESULT, WINNER, -1, -1],
                    [ACK, ACK, ACK_CODE, -1, -1]], dtype=np.int64)  # fmt: skip

# what each robot does with the token
NO_TOKEN, IDLE, ACTIVE, HOSTING, TRANSIT = range(5)


@dataclass
class Outcome:
    """What happened in one round, for the roles and the event log."""

    decided: list[tuple[int, int, int]] = field(default_factory=list)  # (epoch, host, winner)
    became_prime: list[int] = field(default_factory=list)
    declined: list[int] = field(default_factory=list)
    opened: list[tuple[int, int]] = field(default_factory=list)  # (epoch, host)


class Election:
    """Per-robot election state and one flooding round (see the module docstring).

    Parameters
    ----------
    n
        Team size (known to every robot: it sets the ``2(N - 1)`` rounds, times
        ``1 + delay_rounds`` of the layer).
    layer
        The message layer the election talks through.
    host
        Robot holding the token at start-up (the paper's robot 1, here index 0).
    """

    def __init__(self, n: int, layer: MessageLayer, host: int = 0) -> None:
        self.n = n
        self.layer = layer
        # a hop takes 1 + delay_rounds rounds: the open election must reach a candidate
        # N - 1 hops away and its reply come back before the host decides
        self.wait_rounds = 2 * max(n - 1, 1) * (1 + layer.params.delay_rounds)
        self.msg = np.zeros((n, 8))
        self.msg[:, BEST] = np.inf
        self.msg[:, BEST_IDX] = n  # "nobody"
        self.msg[:, WINNER] = -1
        self.token = np.full(n, NO_TOKEN)
        self.token[host] = IDLE
        self.opened_round = np.full(n, -1)
        self.joined = np.zeros(n, dtype=int)  # last epoch robot i put its candidacy in
        self.handled = np.zeros(n, dtype=int)  # last result epoch robot i acted on
        self.candidates: dict[int, list[int]] = {}  # epoch -> who joined (for the event log)
        self.rounds = 0
        self.started = False  # the start-up election was decided

    def holder(self) -> int:
        """The robot holding the token (-1 while it travels to a winner)."""
        held = np.flatnonzero(self.token != NO_TOKEN)
        return int(held[0]) if len(held) else -1

    def open(self, host: int, out: Outcome) -> None:
        """``host`` (the token holder) opens a new election."""
        epoch = int(max(self.msg[:, EPOCH].max(), self.msg[host, EPOCH])) + 1
        self.msg[host, [EPOCH, HOST, BEST, BEST_IDX]] = (epoch, host, np.inf, self.n)
        self.token[host] = HOSTING if self.token[host] != ACTIVE else ACTIVE
        self.opened_round[host] = self.rounds
        self.candidates[epoch] = []
        out.opened.append((epoch, host))

    def round(
        self,
        pairs: np.ndarray,
        candidate: np.ndarray,
        criterion: np.ndarray,
        secondary: np.ndarray,
        wants_election: np.ndarray,
    ) -> Outcome:
        """One flooding round over ``pairs``.

        Parameters
        ----------
        candidate
            ``(n,)`` robots that may stand in an open election now.
        criterion
            ``(n,)`` their criterion (remaining path length ``d_gamma``).
        secondary
            ``(n,)`` robots that may take the prime role if they win.
        wants_election
            ``(n,)`` the prime asks for its succession (it reached its target).
        """
        out = Outcome()
        m = self.msg
        fast = jit.enabled()
        if fast:
            from tether.continuous.exploration.round_kernels import (
                election_busy_after,
                election_busy_before,
            )
        if not fast or election_busy_before(self.token, m, self.opened_round, self.joined,
                                            wants_election, candidate, IDLE, ACTIVE, HOSTING,
                                            NO_TOKEN, EPOCH, RESULT, self.started):  # fmt: skip
            self._open_and_join(candidate, criterion, wants_election, out)
        # flood: every robot merges what its neighbours sent (last values received)
        inbox = self.layer.exchange(pairs, m)
        self.rounds += 1
        if fast:  # the same merge, compiled
            from tether.continuous.exploration.round_kernels import merge_kernel

            merge_kernel(m, inbox.receiver, inbox.values, inbox.valid, _GROUPS, EPOCH, BEST,
                         BEST_IDX)  # fmt: skip
        else:
            ok = inbox.valid
            self._merge(inbox.receiver[ok], inbox.values[ok])
        if not fast or election_busy_after(self.token, m, self.opened_round, self.handled,
                                           self.rounds, self.wait_rounds, HOSTING, ACTIVE,
                                           TRANSIT, RESULT, WINNER):  # fmt: skip
            self._decide(secondary, out)
        return out

    def _open_and_join(
        self,
        candidate: np.ndarray,
        criterion: np.ndarray,
        wants_election: np.ndarray,
        out: Outcome,
    ) -> None:
        """Before the exchange: hosts open elections, candidates join the open ones."""
        m = self.msg
        # the token holder that travels itself takes the role (Algorithm 1, line 8)
        if self.started:
            for h in np.flatnonzero(((self.token == IDLE) | (self.token == HOSTING)) & candidate):
                self._take_own(int(h), out)
        # hosts: the idle token holder polls; the active prime opens when it asks to
        for h in np.flatnonzero(self.token != NO_TOKEN):
            if self.token[h] == IDLE or (self.token[h] == ACTIVE and wants_election[h]
                                         and self.opened_round[h] < 0):  # fmt: skip
                self.open(int(h), out)
        # candidacy: once per open election, with the criterion at joining time
        open_epoch = (m[:, EPOCH] > m[:, RESULT]) & (m[:, EPOCH] > 0)
        join = candidate & open_epoch & (self.joined < m[:, EPOCH])
        for i in np.flatnonzero(join):
            if (criterion[i], i) < (m[i, BEST], m[i, BEST_IDX]):
                m[i, BEST], m[i, BEST_IDX] = criterion[i], i
            self.joined[i] = int(m[i, EPOCH])
            self.candidates.setdefault(int(m[i, EPOCH]), []).append(int(i))

    def _take_own(self, h: int, out: Outcome) -> None:
        """Token holder ``h``, a secondary traveler, wins its own poll now and is prime."""
        m = self.msg
        if self.opened_round[h] < 0:
            self.open(h, out)
        epoch = int(m[h, EPOCH])
        if h not in self.candidates.setdefault(epoch, []):
            self.candidates[epoch].append(h)
        self.opened_round[h] = -1
        self.joined[h] = self.handled[h] = epoch
        m[h, RESULT], m[h, WINNER] = epoch, h
        m[h, ACK], m[h, ACK_CODE] = epoch, TAKEN
        out.decided.append((epoch, h, h))
        self.token[h] = ACTIVE
        out.became_prime.append(h)

    def _decide(self, secondary: np.ndarray, out: Outcome) -> None:
        """After the exchange: hosts decide, winners take or decline, tokens in transit land."""
        m = self.msg
        # hosts decide after 2(N - 1) rounds (times 1 + the layer's delay)
        for h in np.flatnonzero((self.token == HOSTING) | (self.token == ACTIVE)):
            if self.opened_round[h] < 0 or self.rounds - self.opened_round[h] < self.wait_rounds:
                continue
            epoch, best = int(m[h, EPOCH]), int(m[h, BEST_IDX])
            self.opened_round[h] = -1
            self.started = True
            m[h, RESULT], m[h, WINNER] = epoch, (best if best < self.n else -1)
            out.decided.append((epoch, int(h), int(m[h, WINNER])))
            self.token[h] = IDLE if best >= self.n else TRANSIT
        # the winner takes the token or declines it
        news = (m[:, RESULT] > self.handled) & (m[:, WINNER] == np.arange(self.n))
        for w in np.flatnonzero(news):
            self.handled[w] = int(m[w, RESULT])
            take = bool(secondary[w])
            m[w, ACK], m[w, ACK_CODE] = m[w, RESULT], TAKEN if take else DECLINED
            if take:
                self.token[w] = ACTIVE
                out.became_prime.append(int(w))
            else:
                out.declined.append(int(w))
        # a host whose token is in transit hears the acknowledgement (its own, if it won)
        for h in np.flatnonzero(self.token == TRANSIT):
            if m[h, ACK] > m[h, RESULT]:  # a later election exists: the token was taken
                self.token[h] = NO_TOKEN
            elif m[h, ACK] == m[h, RESULT] and m[h, RESULT] > 0:
                self.token[h] = NO_TOKEN if m[h, ACK_CODE] == TAKEN else IDLE

    def _merge(self, recv: np.ndarray, vals: np.ndarray) -> None:
        """Each robot adopts the newest election, result and acknowledgement it heard."""
        m = self.msg
        for field_, take in ((EPOCH, (EPOCH, HOST, BEST, BEST_IDX)), (RESULT, (RESULT, WINNER)),
                             (ACK, (ACK, ACK_CODE))):  # fmt: skip
            newest = np.full(self.n, -np.inf)
            np.maximum.at(newest, recv, vals[:, field_])
            for i in np.flatnonzero(newest > m[:, field_]):
                rows = vals[(recv == i) & (vals[:, field_] == newest[i])]
                m[i, list(take)] = rows[0, list(take)]
        # the same open election: keep the lexicographically smallest candidate
        same = vals[:, EPOCH] == m[recv, EPOCH]
        if not same.any():
            return
        r, b, bi = recv[same], vals[same, BEST], vals[same, BEST_IDX]
        best = smallest_per_receiver(r, b, bi)
        r, b, bi = r[best], b[best], bi[best]
        better = (b < m[r, BEST]) | ((b == m[r, BEST]) & (bi < m[r, BEST_IDX]))
        m[r[better], BEST] = b[better]
        m[r[better], BEST_IDX] = bi[better]
