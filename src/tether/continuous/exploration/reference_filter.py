"""The fourth-order reference filter of the quadrotor experiment (eq. (16), Sec. 4.2).

``q_f'''' = -k1 q_f''' - k2 q_f'' - k3 q_f' + k4 (q - q_f)`` turns the robot's
trajectory ``q_i(t)`` of eq. (1) into a C4 reference ``q_f(t)`` for a real
quadrotor, with gains ``k1..k4 = 44, 707, 5090, 13692`` (poles near -12, -13,
-14, -15: settling in about 0.3 s). In tether it is an option of the
``multi_target`` strategy: the filtered reference is recorded beside the
positions and its largest deviation reported.

The filter is linear, so each control period is integrated exactly: with the
state ``x = (q_f, q_f', q_f'', q_f''')`` per coordinate, ``x+ = A_d x + B_d q``
with the matrix exponential of the companion matrix (zero-order hold on ``q``).
"""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np
import scipy.linalg

from tether import jit

PAPER_GAINS = (44.0, 707.0, 5090.0, 13692.0)


class ReferenceFilter:
    """Eq. (16) for every robot and coordinate, discretised exactly for a period ``dt_s``."""

    def __init__(self, q0: np.ndarray, dt_s: float, gains: tuple[float, ...] = PAPER_GAINS):
        k1, k2, k3, k4 = gains
        a = np.array([[0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1], [-k4, -k3, -k2, -k1]], float)
        b = np.array([0, 0, 0, k4], float)
        m = np.zeros((5, 5))
        m[:4, :4], m[:4, 4] = a, b
        e = scipy.linalg.expm(m * dt_s)  # [[A_d, B_d], [0, 1]]
        self.a_d, self.b_d = e[:4, :4].copy(), e[:4, 4].copy()
        q0 = np.asarray(q0, dtype=float)
        self.state = np.zeros((4,) + q0.shape)  # (derivative order, n, dim)
        self.state[0] = q0

    @property
    def position(self) -> np.ndarray:
        return self.state[0]

    def update(self, q: np.ndarray) -> np.ndarray:
        """Advance one period with input ``q`` (held); returns the filtered positions."""
        self.state = np.tensordot(self.a_d, self.state, axes=1) + self.b_d[:, None, None] * q
        return self.state[0]

    def advance(self, q: np.ndarray) -> tuple[float, float, float]:
        """:meth:`update` with input ``q``, then the largest distance of a reference from
        its robot and the largest speed and acceleration of a reference (compiled when
        kernels run: the same bits)."""
        if jit.enabled():
            self.state, dev, speed, accel = _kernel()(
                self.a_d, self.b_d, self.state, np.ascontiguousarray(q, dtype=float)
            )
            return dev, speed, accel
        dev = np.linalg.norm(self.update(q) - q, axis=1).max()
        speed, accel = (np.linalg.norm(self.state[k], axis=1).max() for k in (1, 2))
        return float(dev), float(speed), float(accel)


@cache
def _kernel() -> Any:
    """The compiled period (:mod:`.reference_filter_kernels`), imported on first use."""
    from tether.continuous.exploration.reference_filter_kernels import reference_step_kernel

    return reference_step_kernel
