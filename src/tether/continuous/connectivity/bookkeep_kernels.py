"""Compiled per-step bookkeeping of the continuous strategies (numba, lazy).

The fast paths of the running records that
:meth:`tether.continuous.exploration.strategy.MultiTargetStrategy._bookkeep` and
:meth:`tether.continuous.connectivity.strategy.ConnectivityStrategy._observe` keep every control
step, used when :func:`tether.jit.enabled`. ``numpy.linalg.norm(x, axis=-1)`` sums a
short row's squares in coordinate order, which the loops below repeat; ``sqrt`` is
monotone and correctly rounded, so the largest (smallest) of the norms is the ``sqrt``
of the largest (smallest) sum: the same bits as the numpy reference
(``tests/test_bookkeep_kernels.py``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def _sq(a, i, b, j):  # noqa: ANN001, ANN202
    """``sum_d (a[i, d] - b[j, d])^2`` in coordinate order."""
    acc = 0.0
    for d in range(a.shape[1]):
        x = a[i, d] - b[j, d]
        acc += x * x
    return acc


@njit(cache=True)
def travel_stretch_kernel(travelled, q, q_new, explorer):  # noqa: ANN001, ANN201
    """Add ``|q_new_i - q_i|`` to ``travelled`` in place; the explorers' largest distance.

    Returns ``max_{i, j explorers} |q_new_i - q_new_j|`` (``-1.0`` with fewer than two
    explorers), as ``numpy.linalg.norm(q_new[ex, None] - q_new[None, ex], axis=-1).max()``.
    """
    n = q.shape[0]
    for i in range(n):
        travelled[i] += math.sqrt(_sq(q_new, i, q, i))
    count = 0
    best = 0.0
    for i in range(n):
        if not explorer[i]:
            continue
        count += 1
        for j in range(i + 1, n):
            if explorer[j]:
                s = _sq(q_new, i, q_new, j)
                if s > best:
                    best = s
    return math.sqrt(best) if count > 1 else -1.0


@njit(cache=True)
def min_link_distance_kernel(q, pairs):  # noqa: ANN001, ANN201
    """``min_k |q[pairs[k, 0]] - q[pairs[k, 1]]|`` (``inf`` without pairs)."""
    best = np.inf
    for k in range(pairs.shape[0]):
        s = _sq(q, pairs[k, 0], q, pairs[k, 1])
        if s < best:
            best = s
    return math.sqrt(best)


def warm_up() -> None:
    """Compile (or load) the kernels for 2-D and 3-D teams."""
    for dim in (2, 3):
        q = np.zeros((3, dim))
        travel_stretch_kernel(np.zeros(3), q, q + 1.0, np.ones(3, dtype=np.bool_))
        min_link_distance_kernel(q, np.array([[0, 1]], dtype=np.int64))
