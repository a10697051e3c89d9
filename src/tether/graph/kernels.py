"""Compiled kernels of the graph layer (numba; imported only by callers that use kernels).

:func:`laplacian_dense_kernel` builds exactly the matrix of
:func:`tether.graph.structure.laplacian_dense`: the diagonal is numpy's row sum, whose
pairwise summation (:func:`pairwise_sum`, numpy's ``pairwise_sum`` with blocks of 8 and
128) is reproduced term for term, so both give the same bits and every eigensolver the
same answer.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def block_sum(a, lo, n):  # noqa: ANN001, ANN201
    """numpy's pairwise sum of ``a[lo:lo + n]`` for ``n <= 128``: eight running sums."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += a[lo + i]
        return res
    r0, r1, r2, r3 = a[lo], a[lo + 1], a[lo + 2], a[lo + 3]
    r4, r5, r6, r7 = a[lo + 4], a[lo + 5], a[lo + 6], a[lo + 7]
    i = 8
    while i < n - (n % 8):
        r0 += a[lo + i]
        r1 += a[lo + i + 1]
        r2 += a[lo + i + 2]
        r3 += a[lo + i + 3]
        r4 += a[lo + i + 4]
        r5 += a[lo + i + 5]
        r6 += a[lo + i + 6]
        r7 += a[lo + i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[lo + i]
        i += 1
    return res


@njit(cache=True)
def pairwise_sum(a, lo, n):  # noqa: ANN001, ANN201
    """``numpy.add.reduce`` of ``a[lo:lo + n]`` (contiguous), in numpy's order."""
    if n <= 128:
        return block_sum(a, lo, n)
    n2 = n // 2
    n2 -= n2 % 8
    return pairwise_sum(a, lo, n2) + pairwise_sum(a, lo + n2, n - n2)


@njit(cache=True)
def laplacian_dense_kernel(n, pairs, w):  # noqa: ANN001, ANN201
    """Dense ``L = diag(W 1) - W``, bit for bit :func:`~tether.graph.structure.laplacian_dense`."""
    lap = np.zeros((n, n))
    for k in range(len(pairs)):
        lap[pairs[k, 0], pairs[k, 1]] = -w[k]
    for k in range(len(pairs)):
        lap[pairs[k, 1], pairs[k, 0]] = -w[k]
    flat = lap.ravel()
    for r in range(n):
        lap[r, r] = -(0.0 + pairwise_sum(flat, r * n, n))
    return lap


@njit(cache=True)
def pairs_within_kernel(q, r):  # noqa: ANN001, ANN201
    """Pairs ``i < j`` with ``sum_d (q_i - q_j)_d^2 <= r^2`` in lexicographic order.

    :func:`tether.graph.structure.pairs_within`'s result (``cKDTree.query_pairs``
    tests squared distances summed in coordinate order against ``r * r`` the same
    way); all pairs are tested (teams of up to a few hundred robots).
    """
    n = q.shape[0]
    r2 = r * r
    # two passes, count then fill: an output array that may be replaced inside the loop
    # costs a reference count per pair (2-3x the loop)
    m = 0
    for i in range(n):
        for j in range(i + 1, n):
            m += sq_dist(q, i, j) <= r2
    out = np.empty((m, 2), np.int64)
    m = 0
    for i in range(n):
        for j in range(i + 1, n):
            if sq_dist(q, i, j) <= r2:
                out[m, 0], out[m, 1] = i, j
                m += 1
    return out


@njit(cache=True, inline="always")
def sq_between(a, i, b, j):  # noqa: ANN001, ANN202
    """``sum_d (a[i, d] - b[j, d])^2``, summed in coordinate order."""
    acc = 0.0
    for d in range(a.shape[1]):
        x = a[i, d] - b[j, d]
        acc += x * x
    return acc


@njit(cache=True, inline="always")
def sq_dist(q, i, j):  # noqa: ANN001, ANN202
    """``sum_d (q_i - q_j)_d^2``, summed in coordinate order."""
    return sq_between(q, i, q, j)


@njit(cache=True)
def component_count_kernel(n, pairs):  # noqa: ANN001, ANN201
    """Number of connected components (union-find with path halving)."""
    parent = np.arange(n)
    count = n
    for k in range(len(pairs)):
        a, b = pairs[k, 0], pairs[k, 1]
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        while parent[b] != b:
            parent[b] = parent[parent[b]]
            b = parent[b]
        if a != b:
            parent[a] = b
            count -= 1
    return count
