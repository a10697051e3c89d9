"""Compiled per-step bookkeeping of the ``connectivity`` strategy (numba, lazy).

The fast path of the shortest link that
:meth:`tether.continuous.connectivity.strategy.ConnectivityStrategy._observe` records
every control step, used when :func:`tether.jit.enabled`. ``numpy.linalg.norm(x,
axis=-1)`` sums a short row's squares in coordinate order, which
:func:`tether.graph.kernels.sq_between` repeats; ``sqrt`` is monotone and correctly
rounded, so the smallest of the norms is the ``sqrt`` of the smallest sum: the same
bits as the numpy reference (``tests/test_step_fast_paths.py``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tether.graph.kernels import sq_between


@njit(cache=True)
def min_link_distance_kernel(q, pairs):  # noqa: ANN001, ANN201
    """``min_k |q[pairs[k, 0]] - q[pairs[k, 1]]|`` (``inf`` without pairs)."""
    best = np.inf
    for k in range(pairs.shape[0]):
        s = sq_between(q, pairs[k, 0], q, pairs[k, 1])
        if s < best:
            best = s
    return math.sqrt(best)


def warm_up() -> None:
    """Compile (or load) the kernel for 2-D and 3-D teams."""
    for dim in (2, 3):
        q = np.zeros((3, dim))
        min_link_distance_kernel(q, np.array([[0, 1]], dtype=np.int64))
