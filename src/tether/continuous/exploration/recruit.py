"""Recruiting helpers for a stalled prime traveler (beyond the paper).

The completeness of Algorithm 1 (Prop. 2) rests on Assumption 1: the prime
traveler reaches its target in finite time whatever the others do. In a
cluttered scene that can fail: a prime at the end of a chain, held by one link
whose weight falls to 0 past a building edge, meets a connectivity force that
grows without bound while its traveling force is bounded (10 N), and the
connectors, whose own force is 0, are not pulled along by the team's gradient
(the town trials of Fig. 9 that stalled; ``docs/multi_target.md``).

The remedy here: a prime whose remaining path has not shrunk by ``Rgrid`` for
``help_after_s`` asks for help. The request floods through the message layer
(so loss and delay reach it) to a depth that grows by one hop every further
``help_after_s`` of stall, up to ``max_hops``. A connector or secondary
traveler that hears it at hop ``h`` from the prime follows the neighbour it
heard it from (its parent, one hop closer to the prime): the force
``f = sat(k_p (d - R's)^+ u - k_v v, F_max)`` pulls it to within ``R's`` of the
parent's last broadcast position (``u`` the unit vector towards it, ``d`` the
distance), the distance below which the range factor of the link weight is 1.
A secondary's own traveling force is suspended while it helps. Anchors relay
the request but stay at their targets. The request ends as soon as the prime
makes progress again; if it still has none after ``stall_timeout_s``, the
target is dropped as before.

Each robot's state uses only what its neighbours sent: its hop count is one
more than the smallest hop count among the requests it holds whose depth
allows another hop (ties to the lower sender index).

Optionally (``help_lambda_factor = g``, default off) a helper's own connectivity
force is scaled by ``g`` while it helps: ``M dv/dt = -B v + g f_lambda + f_help``.
Without it a team that has closed a loop round an obstacle it cannot overfly holds
every link of the loop (each one raises lambda2, so ``f_lambda`` defends it with up
to ~100 N against the helpers' 10 N), and a prime hanging from the loop cannot
reach a target beyond the loop's reach (``docs/multi_target.md``, *The dropped
target*). Scaled down, it lets the helpers' pull towards their parents (a
breadth-first tree rooted at the prime) win over the defence of links the prime
does not need. Connectivity still holds: the integrator accepts a sub-step only if
lambda2 keeps half its margin (:mod:`tether.continuous.connectivity.dynamics`), and the other
robots' force is unchanged. Measured on the campaign's helped trials with
``benchmarks/rerun_helped.py`` (``docs/multi_target.md``).
"""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np

from tether import jit
from tether.comm import MessageLayer, smallest_per_receiver
from tether.continuous.exploration.travel import saturate

NO_HELP = np.inf


class HelpFlood:
    """The help request of a stalled prime, flooded one hop per message round.

    Each robot broadcasts ``(hop, depth, x, y[, z])``: its hop count from the
    stalled prime (``inf``: not in the request) and the request's depth.

    Parameters
    ----------
    n, dim
        Team size and space dimension.
    layer
        The message layer the request travels through.
    """

    def __init__(self, n: int, dim: int, layer: MessageLayer) -> None:
        self.layer = layer
        self.max_age = layer.params.delay_rounds + 2  # older mail is not a live request
        self._quiet = True  # the last round sent no request: rounds may be skipped
        self.hop = np.full(n, NO_HELP)
        self.depth = np.zeros(n)
        self.parent = np.full(n, -1)
        self.parent_m = np.full((n, dim), np.nan)

    def round(self, pairs: np.ndarray, q: np.ndarray, prime: int, depth: int) -> None:
        """One exchange: the prime (``depth > 0``: asking) sets hop 0, the others relay.

        While nobody asks and the last round carried no request, the round is
        skipped (every robot would send "no request" and hear nothing else).
        """
        if prime >= 0:
            asking = depth > 0
            self.hop[prime], self.depth[prime] = (0.0, float(depth)) if asking else (NO_HELP, 0.0)
        quiet = not np.isfinite(self.hop).any()
        if quiet and self._quiet:
            return
        self._quiet = quiet
        sent = np.column_stack([self.hop, self.depth, q])
        inbox = self.layer.exchange(pairs, sent)
        ok = (inbox.valid & (inbox.age <= self.max_age)
              & (inbox.values[:, 0] + 1 <= inbox.values[:, 1]))  # fmt: skip
        recv, send, vals = inbox.receiver[ok], inbox.sender[ok], inbox.values[ok]
        n = len(self.hop)
        hop, depth, parent = np.full(n, NO_HELP), np.zeros(n), np.full(n, -1)
        parent_m = np.full_like(self.parent_m, np.nan)
        best = smallest_per_receiver(recv, vals[:, 0], send)  # smallest hop, lower index
        r = recv[best]
        hop[r], depth[r], parent[r] = vals[best, 0] + 1, vals[best, 1], send[best]
        parent_m[r] = vals[best, 2:]
        if prime >= 0 and self.hop[prime] == 0:  # the prime keeps asking whatever it hears
            hop[prime], depth[prime], parent[prime] = 0.0, self.depth[prime], -1
            parent_m[prime] = np.nan
        self.hop, self.depth, self.parent, self.parent_m = hop, depth, parent, parent_m

    def helpers(self, may_help: np.ndarray) -> np.ndarray:
        """Indices of the robots that help now (``may_help``: connectors and secondaries)."""
        return np.flatnonzero((self.hop >= 1) & np.isfinite(self.hop) & may_help)


def help_depth(stalled_s: float, help_after_s: float, max_hops: int, base: int = 0) -> int:
    """Hops the request reaches after ``stalled_s`` without progress (0: no request).

    ``base``: the depth a request kept from an earlier stall of the same prime
    (:class:`RequestDepth` with ``until="arrival"``); a new stall deepens it.
    """
    if not np.isfinite(stalled_s) or stalled_s < help_after_s:
        return 0
    return int(min(max_hops, base + 1 + (stalled_s - help_after_s) // help_after_s))


class RequestDepth:
    """How deep the prime's help request reaches, step by step (the prime's own state).

    ``update`` gives the depth and what changed: ``"requested"`` when the request
    starts or deepens, ``"ended"`` when it stops. The request starts after
    ``after_s`` without progress and deepens by one hop per further ``after_s``
    (:func:`help_depth`). What ends it:

    * ``until="progress"``: the prime's next progress by ``Rgrid``; a new stall starts
      again from 1 hop;
    * ``until="arrival"``: only the end of the prime's turn (it reached or dropped its
      target, or another robot became prime). Progress keeps the request at its depth,
      and each later stall of ``after_s`` adds a hop. A prime crawling in bursts (each
      burst of help lets it progress, then it stalls again) thus keeps its helpers and
      draws more, instead of waiting ``after_s`` alone before every burst.
    """

    def __init__(self, after_s: float | None, max_hops: int, until: str = "progress") -> None:
        self.after_s, self.max_hops, self.sticky = after_s, max_hops, until == "arrival"
        self.depth = 0
        self._prime, self._base = -1, 0

    def update(self, prime: int, stalled_s: float) -> tuple[int, str | None]:
        """The depth for the current ``prime`` (-1: none), stalled for ``stalled_s``."""
        same = prime == self._prime
        if not same:  # a new prime (or none): its own request, from nothing
            self._prime, self._base = prime, 0
        depth = 0
        if prime >= 0 and self.after_s is not None:
            depth = help_depth(stalled_s, self.after_s, self.max_hops, self._base)
            if self.sticky and same and depth == 0 and self.depth > 0:
                self._base = depth = self.depth  # progress: the request keeps its depth
        change = None
        if depth > self.depth:
            change = "requested"
        elif depth == 0 and self.depth > 0:
            change = "ended"
        self.depth = depth
        return depth, change


def help_force(
    q: np.ndarray,
    v: np.ndarray,
    parent_m: np.ndarray,
    *,
    keep_m: float,
    kp: float,
    kv: float,
    max_force_n: float,
) -> np.ndarray:
    """``sat(k_p (d - keep) u - k_v v, F_max)`` towards the parents beyond ``keep_m``, ``(h, dim)``.

    A helper already within ``keep_m`` of its parent gets no force (it moves as a
    connector, by the connectivity force alone).
    """
    gap = parent_m - q
    d = np.linalg.norm(gap, axis=1, keepdims=True)
    far = d > keep_m
    pull = np.where(far, kp * (d - keep_m) * gap / np.maximum(d, 1e-12) - kv * v, 0.0)
    return saturate(pull, max_force_n)


def help_rows(
    q: np.ndarray,
    v: np.ndarray,
    f: np.ndarray,
    f_lambda: np.ndarray,
    helpers: np.ndarray,
    parent_m: np.ndarray,
    *,
    keep_m: float,
    kp: float,
    kv: float,
    max_force_n: float,
    lambda_factor: float | None,
) -> np.ndarray:
    """``f`` (the team's external force) with the rows of ``helpers`` replaced, in place.

    Each helper follows its parent (:func:`help_force`; a secondary's ``f_i`` too); with
    ``lambda_factor = g`` its ``f_lambda`` is scaled by ``g``: ``(1 - g) f_lambda`` is
    subtracted. Compiled when kernels run (:mod:`.recruit_kernels`, the same bits).
    """
    if jit.enabled():
        factor = np.nan if lambda_factor is None else float(lambda_factor)
        _kernel()(q, v, f, f_lambda, np.asarray(helpers, dtype=np.int64), parent_m,
                  float(keep_m), float(kp), float(kv), float(max_force_n), factor)  # fmt: skip
        return f
    f[helpers] = help_force(q[helpers], v[helpers], parent_m, keep_m=keep_m, kp=kp, kv=kv,
                            max_force_n=max_force_n)  # fmt: skip
    if lambda_factor is not None:
        f[helpers] -= (1.0 - lambda_factor) * f_lambda[helpers]
    return f


@cache
def _kernel() -> Any:
    """:func:`.recruit_kernels.help_rows_kernel`, imported on first use (numba)."""
    from tether.continuous.exploration.recruit_kernels import help_rows_kernel

    return help_rows_kernel
