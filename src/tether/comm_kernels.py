"""Compiled rounds of the message layer: delivery without delay, mailboxes re-aligned (numba).

The fast paths of :meth:`tether.comm.MessageLayer.exchange` when messages arrive in
the round they are sent, and of its re-alignment of the mailboxes with a new link
set, used when :func:`tether.jit.enabled`: the same links, the same loss draws (drawn
by the caller from the layer's generator, one per directed link, as the reference
draws them), the same mailboxes and ages. For a team of 35 robots the reference is a
dozen numpy calls per round.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def deliver_kernel(mail, sent_at, values, recv, send, dead_from, draws, loss, now):  # noqa: ANN001, ANN201
    """Deliver ``values[send]`` into ``mail`` over the directed links; ``(sent, delivered, age)``.

    A message is sent when both ends are alive (``now < dead_from``) and delivered
    unless its draw is below ``loss`` (``draws`` empty: no loss); a delivered message
    overwrites its mailbox row and its ``sent_at`` becomes ``now``. ``age`` is
    ``now - sent_at`` (-1 where nothing was ever received).
    """
    e = len(recv)
    sent = 0
    delivered = 0
    lossy = len(draws) > 0
    for k in range(e):
        if not (now < dead_from[recv[k]] and now < dead_from[send[k]]):
            continue
        sent += 1
        if lossy and not draws[k] >= loss:
            continue
        for c in range(mail.shape[1]):
            mail[k, c] = values[send[k], c]
        sent_at[k] = now
        delivered += 1
    age = np.empty(e, np.int64)
    for k in range(e):
        age[k] = now - sent_at[k] if sent_at[k] >= 0 else -1
    return sent, delivered, age


@njit(cache=True)
def relink_kernel(old_codes, old_mail, old_sent_at, codes, n):  # noqa: ANN001, ANN201
    """Mailboxes and send rounds for the links ``codes`` (``receiver * n + sender``).

    A link kept from ``old_codes`` keeps its mailbox row and send round; a new link
    gets ``nan`` and -1 (mail over vanished links is dropped). Codes are unique.
    """
    slot = np.full(n * n, -1, np.int64)
    for s in range(len(old_codes)):
        slot[old_codes[s]] = s
    k = old_mail.shape[1]
    mail = np.full((len(codes), k), np.nan)
    sent_at = np.full(len(codes), -1, np.int64)
    for t in range(len(codes)):
        s = slot[codes[t]]
        if s >= 0:
            for c in range(k):
                mail[t, c] = old_mail[s, c]
            sent_at[t] = old_sent_at[s]
    return mail, sent_at


def warm_up() -> None:
    """Compile (or load) the kernel for the mailboxes of one and of several values."""
    link = np.zeros(1, dtype=np.int64)
    for k in (1, 8):
        deliver_kernel(np.zeros((1, k)), np.full(1, -1, dtype=np.int64), np.zeros((1, k)), link,
                       link, np.full(1, 10, dtype=np.int64), np.zeros(1), 0.1, 0)  # fmt: skip
        relink_kernel(link, np.zeros((1, k)), link, link, 2)
