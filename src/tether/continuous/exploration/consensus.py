"""The consensus estimate of the prime traveler's efficiency (eq. (13)).

Every robot but the prime traveler ``p`` runs
``d/dt Lambda_hat_i = k_Lambda sum_{j in N_i} (Lambda_hat_j - Lambda_hat_i)``;
the prime sets ``Lambda_hat_p = Lambda_p``. The estimates are saturated to
``[0, 1]`` (Sec. 3.7). Robots exchange their estimates through the message layer
(:class:`tether.comm.MessageLayer`), so with loss or delay a robot uses the last
value it received from each neighbour.

Discretisation: forward Euler over a round of ``h`` seconds with the step of
each robot limited to ``min(k_Lambda h, 1 / (deg_i + 1))``, which makes every
update a convex combination of received values (stable for any ``h`` and
degree, and it keeps the estimates in ``[0, 1]``); it is eq. (13)'s Euler step
whenever ``k_Lambda h (deg_i + 1) <= 1``.
"""

from __future__ import annotations

import numpy as np

from tether import jit
from tether.comm import MessageLayer


class EfficiencyConsensus:
    """Estimates ``Lambda_hat_i`` of the prime traveler's efficiency (start: 0, Alg. 1 line 12)."""

    def __init__(self, n: int, layer: MessageLayer, gain_per_s: float) -> None:
        if not gain_per_s > 0:
            raise ValueError(f"gain_per_s must be > 0 (got {gain_per_s})")
        self.layer = layer
        self.gain_per_s = gain_per_s
        self.estimate = np.zeros(n)

    def round(self, pairs: np.ndarray, dt_s: float, prime: int, efficiency: float) -> None:
        """One exchange and update over ``dt_s``; ``prime < 0`` when there is none."""
        if prime >= 0:
            self.estimate[prime] = efficiency
        inbox = self.layer.exchange(pairs, self.estimate[:, None])
        if jit.enabled():  # the same update, compiled
            from tether.continuous.exploration.round_kernels import consensus_kernel

            new = consensus_kernel(self.estimate, inbox.receiver, inbox.values[:, 0],
                                   inbox.valid, self.gain_per_s * dt_s)  # fmt: skip
            if prime >= 0:
                new[prime] = efficiency
            self.estimate = new
            return
        ok = inbox.valid
        recv, diff = inbox.receiver[ok], inbox.values[ok, 0] - self.estimate[inbox.receiver[ok]]
        n = len(self.estimate)
        total = np.bincount(recv, diff, n)
        degree = np.bincount(recv, minlength=n)
        step = np.minimum(self.gain_per_s * dt_s, 1.0 / (degree + 1.0))
        new = np.clip(self.estimate + step * total, 0.0, 1.0)
        if prime >= 0:
            new[prime] = efficiency
        self.estimate = new
