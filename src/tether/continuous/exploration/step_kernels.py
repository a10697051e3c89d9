"""Compiled per-step tests and bookkeeping of ``multi_target`` (numba, lazy).

The fast paths, used when :func:`tether.jit.enabled`, of the anchors' distance test of
:meth:`tether.continuous.exploration.strategy.MultiTargetStrategy.evaluate`
(:func:`any_row_beyond`) and of the travelled distances and team stretch that
:meth:`~tether.continuous.exploration.strategy.MultiTargetStrategy._bookkeep` records
every control step (:func:`travel_stretch_kernel`). Both repeat the numpy reference's
sums of squares in coordinate order, so the same bits
(``tests/test_anchor_leaves.py``, ``tests/test_step_fast_paths.py``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tether.continuous.connectivity.pair_kernels import row_norm
from tether.graph.kernels import sq_between


@njit(cache=True)
def any_row_beyond(q, rows, targets, r):  # noqa: ANN001, ANN201
    """``numpy.any(numpy.linalg.norm(q[rows] - targets, axis=1) >= r)``, the same
    distances (:func:`row_norm`) without numpy's per-call overhead.

    The anchor test of :meth:`tether.continuous.exploration.strategy.MultiTargetStrategy.evaluate`
    (an anchor must stay within ``Rz`` of its target, Nestmeyer et al. 2017, Sec. 4).
    """
    dim = q.shape[1]
    diff = np.empty(dim)
    for k in range(len(rows)):
        for d in range(dim):
            diff[d] = q[rows[k], d] - targets[k, d]
        if row_norm(diff) >= r:
            return True
    return False


@njit(cache=True)
def travel_stretch_kernel(travelled, q, q_new, explorer):  # noqa: ANN001, ANN201
    """Add ``|q_new_i - q_i|`` to ``travelled`` in place; the explorers' largest distance.

    Returns ``max_{i, j explorers} |q_new_i - q_new_j|`` (``-1.0`` with fewer than two
    explorers), as ``numpy.linalg.norm(q_new[ex, None] - q_new[None, ex], axis=-1).max()``.
    """
    n = q.shape[0]
    for i in range(n):
        travelled[i] += math.sqrt(sq_between(q_new, i, q, i))
    count = 0
    best = 0.0
    for i in range(n):
        if not explorer[i]:
            continue
        count += 1
        for j in range(i + 1, n):
            if explorer[j]:
                s = sq_between(q_new, i, q_new, j)
                if s > best:
                    best = s
    return math.sqrt(best) if count > 1 else -1.0


def warm_up() -> None:
    """Compile (or load) the kernels for 2-D and 3-D teams."""
    for dim in (2, 3):
        q = np.zeros((3, dim))
        travel_stretch_kernel(np.zeros(3), q, q + 1.0, np.ones(3, dtype=np.bool_))
        rows = np.array([0, 2], dtype=np.int64)
        any_row_beyond(q, rows, q[rows], 1.0)
