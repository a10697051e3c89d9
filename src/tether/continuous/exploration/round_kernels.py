"""Compiled updates of the message rounds: the election's merge, the consensus step (numba).

The fast paths of :meth:`tether.continuous.exploration.election.Election._merge` and of the update
of :meth:`tether.continuous.exploration.consensus.EfficiencyConsensus.round`, used when
:func:`tether.jit.enabled`. Each robot is updated from its own row and the messages in
its inbox only (what :class:`tether.comm.MessageLayer` delivered), exactly as the numpy
reference does it: the same winners, the same rows adopted (the first in inbox order
among equals), and sums in inbox order (``np.bincount``'s), so the same bits.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def merge_kernel(m, recv, vals, valid, groups, epoch, best, best_idx):  # noqa: ANN001, ANN201
    """Election merge in place on ``m`` ``(n, k)`` from the inbox rows ``recv``, ``vals``
    where ``valid`` (something was received over that link).

    ``groups`` ``(g, 1 + w)``: per group the field compared and the ``w`` fields
    adopted with it (-1 pads), applied one after the other: robot ``i`` adopts the
    first inbox row with the largest value of the field when that is newer than its
    own. Then, among the rows of the election robot ``i`` now has (same ``epoch``
    field), the lexicographically smallest ``(best, best_idx)`` replaces its own if
    smaller.
    """
    n = m.shape[0]
    e = len(recv)
    newest = np.empty(n)
    newer = np.empty(n, np.bool_)
    for g in range(groups.shape[0]):
        f = groups[g, 0]
        newest[:] = -np.inf
        for k in range(e):
            r = recv[k]
            if not valid[k]:
                continue
            if vals[k, f] > newest[r] or (np.isnan(vals[k, f]) and not np.isnan(newest[r])):
                newest[r] = vals[k, f]  # np.maximum.at propagates nan
        for r in range(n):
            newer[r] = newest[r] > m[r, f]
        for k in range(e):
            r = recv[k]
            if valid[k] and newer[r] and vals[k, f] == newest[r]:
                for c in range(1, groups.shape[1]):
                    col = groups[g, c]
                    if col >= 0:
                        m[r, col] = vals[k, col]
                newer[r] = False
    has = np.zeros(n, np.bool_)
    b_min = np.empty(n)
    bi_min = np.empty(n)
    for k in range(e):
        r = recv[k]
        if valid[k] and vals[k, epoch] == m[r, epoch]:
            b, bi = vals[k, best], vals[k, best_idx]
            if not has[r] or b < b_min[r] or (b == b_min[r] and bi < bi_min[r]):
                has[r] = True
                b_min[r], bi_min[r] = b, bi
    for r in range(n):
        if has[r] and (b_min[r] < m[r, best] or (b_min[r] == m[r, best]
                                                  and bi_min[r] < m[r, best_idx])):  # fmt: skip
            m[r, best] = b_min[r]
            m[r, best_idx] = bi_min[r]


@njit(cache=True)
def consensus_kernel(estimate, recv, values, valid, gain_dt):  # noqa: ANN001, ANN201
    """One consensus update (eq. (13), limited Euler step) from the inbox, clipped to [0, 1]."""
    n = len(estimate)
    total = np.zeros(n)
    degree = np.zeros(n)
    for k in range(len(recv)):
        if valid[k]:
            r = recv[k]
            total[r] += values[k] - estimate[r]
            degree[r] += 1.0
    new = np.empty(n)
    for r in range(n):
        step = min(gain_dt, 1.0 / (degree[r] + 1.0))
        new[r] = min(max(estimate[r] + step * total[r], 0.0), 1.0)
    return new


@njit(cache=True)
def election_busy_before(token, msg, opened_round, joined, wants, candidate, idle, active,
                         hosting, no_token, epoch, result, started):  # noqa: ANN001, ANN201, PLR0913  # fmt: skip
    """Whether a round of :meth:`~tether.continuous.exploration.election.Election.round` opens an
    election, lets the token holder take the role or takes a candidacy before its
    exchange (the same tests, robot by robot).

    False lets the caller skip these steps: they would do nothing.
    """
    for h in range(len(token)):
        if token[h] != no_token and (token[h] == idle or (token[h] == active and wants[h]
                                                          and opened_round[h] < 0)):  # fmt: skip
            return True
        if started and candidate[h] and token[h] == hosting:
            return True
    for i in range(len(token)):
        e = msg[i, epoch]
        if candidate[i] and e > msg[i, result] and e > 0 and joined[i] < e:
            return True
    return False


@njit(cache=True)
def election_busy_after(token, msg, opened_round, handled, rounds, wait_rounds, hosting,
                        active, transit, result, winner):  # noqa: ANN001, ANN201  # fmt: skip
    """Whether a round of :meth:`~tether.continuous.exploration.election.Election.round` decides an
    election, delivers a result to its winner or moves a token in transit after its
    exchange (the same tests). False lets the caller skip those steps.
    """
    for h in range(len(token)):
        t = token[h]
        if t == transit:
            return True
        hosts = t == hosting or t == active  # noqa: SIM109  (numba: no tuple membership)
        if hosts and opened_round[h] >= 0 and rounds - opened_round[h] >= wait_rounds:
            return True
        if msg[h, result] > handled[h] and msg[h, winner] == h:
            return True
    return False


def warm_up() -> None:
    """Compile (or load) the round kernels on a two-robot inbox."""
    recv = np.array([0, 1], dtype=np.int64)
    vals = np.zeros((2, 8))
    valid = np.ones(2, dtype=np.bool_)
    groups = np.array([[0, 0, 1, 2, 3], [4, 4, 5, -1, -1], [6, 6, 7, -1, -1]], dtype=np.int64)
    merge_kernel(np.zeros((2, 8)), recv, vals, valid, groups, 0, 2, 3)
    consensus_kernel(np.zeros(2), recv, vals[:, 0].copy(), valid, 0.5)
    token, opened, count = np.zeros(2, np.int64), np.full(2, -1), np.zeros(2, np.int64)
    flags = np.zeros(2, dtype=np.bool_)
    election_busy_before(token, vals, opened, count, flags, flags, 1, 2, 3, 0, 0, 4, True)
    election_busy_after(token, vals, opened, count, 1, 2, 3, 2, 4, 4, 5)
