"""One period of the reference filter of eq. (16) and its peaks, compiled (numba, lazy).

The fast path, used when :func:`tether.jit.enabled`, of
:meth:`tether.continuous.exploration.reference_filter.ReferenceFilter.advance`: the
state update ``x+ = A_d x + B_d q`` with ``numpy.dot`` on the state flattened to
``(4, n * dim)`` (the matrix product ``numpy.tensordot`` makes: the same BLAS call, the
same bits), then the largest deviation, speed and acceleration of a reference as
``numpy.linalg.norm(rows, axis=1).max()`` finds them (:func:`row_norm`: the squares
summed in coordinate order). ``tests/test_multi_target_laws.py`` compares both paths.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from tether.continuous.connectivity.pair_kernels import row_norm


@njit(cache=True)
def reference_step_kernel(a_d, b_d, state, q):  # noqa: ANN001, ANN201
    """``(state+, deviation, speed, acceleration)``: the new ``(4, n, dim)`` state and
    the largest ``|q_f - q|``, ``|q_f'|`` and ``|q_f''|`` of a robot after it."""
    n, dim = q.shape
    out = np.dot(a_d, state.reshape(4, n * dim)).reshape(4, n, dim)
    for k in range(4):
        for i in range(n):
            for c in range(dim):
                out[k, i, c] += b_d[k] * q[i, c]
    dev = speed = accel = 0.0
    diff = np.empty(dim)
    for i in range(n):
        for c in range(dim):
            diff[c] = out[0, i, c] - q[i, c]
        dev = max(dev, row_norm(diff))
        speed = max(speed, row_norm(out[1, i]))
        accel = max(accel, row_norm(out[2, i]))
    return out, dev, speed, accel


def warm_up() -> None:
    """Compile (or load) the kernel for 2-D and 3-D teams."""
    for dim in (2, 3):
        reference_step_kernel(np.eye(4), np.ones(4), np.zeros((4, 3, dim)), np.ones((3, dim)))
