"""Compiled kernels for a Laplacian kept as its list of links (numba).

The arithmetic of :mod:`tether.graph.links`'s numpy reference, loop by loop, so that
both give the same bits (tests compare them exactly): the product ``L x`` sums each
node's terms in link order (as ``numpy.bincount`` does), the shifted matrix's diagonal
its links' weights in link order, and the perturbation bound each node's changes in
key order.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def canonical_kernel(n, pairs, w):  # noqa: ANN001, ANN201
    """Links of weight ``> 0`` of pairs already sorted with ``i < j`` and unique, and degrees.

    Returns ``ok, lo, hi, w, keys, deg``; ``ok`` is False (and the rest empty) when the
    pairs are not in that form: the caller sorts them then.
    """
    m = len(w)
    keep = 0
    last = -1
    for k in range(m):
        a, b = pairs[k, 0], pairs[k, 1]
        if not a < b:
            if a == b:
                continue
            return False, pairs[:0, 0].copy(), pairs[:0, 0].copy(), w[:0].copy(), \
                pairs[:0, 0].copy(), np.zeros(0)  # fmt: skip
        key = a * n + b
        if key <= last:
            return False, pairs[:0, 0].copy(), pairs[:0, 0].copy(), w[:0].copy(), \
                pairs[:0, 0].copy(), np.zeros(0)  # fmt: skip
        last = key
        if w[k] > 0:
            keep += 1
    lo = np.empty(keep, np.int64)
    hi = np.empty(keep, np.int64)
    wk = np.empty(keep)
    keys = np.empty(keep, np.int64)
    deg_lo = np.zeros(n)
    deg_hi = np.zeros(n)
    e = 0
    for k in range(m):
        a, b = pairs[k, 0], pairs[k, 1]
        if a < b and w[k] > 0:
            lo[e], hi[e], wk[e], keys[e] = a, b, w[k], a * n + b
            deg_lo[a] += w[k]
            deg_hi[b] += w[k]
            e += 1
    return True, lo, hi, wk, keys, deg_lo + deg_hi


@njit(cache=True)
def product_kernel(n, lo, hi, w, x):  # noqa: ANN001, ANN201
    """``L x`` for ``L = sum_k w_k (e_lo - e_hi)(e_lo - e_hi)'``."""
    a = np.zeros(n)
    b = np.zeros(n)
    for k in range(len(w)):
        d = w[k] * (x[lo[k]] - x[hi[k]])
        a[lo[k]] += d
        b[hi[k]] += d
    return a - b


@njit(cache=True)
def change_kernel(n, keys_a, lo_a, hi_a, w_a, keys_b, lo_b, hi_b, w_b):  # noqa: ANN001, ANN201
    """Each node's ``sum_j |w_b - w_a|`` over the union of two sorted, unique key lists.

    A link in one list only counts with weight 0 in the other.
    """
    acc_lo = np.zeros(n)
    acc_hi = np.zeros(n)
    i = 0
    j = 0
    na, nb = len(keys_a), len(keys_b)
    while i < na or j < nb:
        if j >= nb or (i < na and keys_a[i] < keys_b[j]):
            d, u, v = abs(0.0 - w_a[i]), lo_a[i], hi_a[i]
            i += 1
        elif i >= na or keys_b[j] < keys_a[i]:
            d, u, v = abs(w_b[j] - 0.0), lo_b[j], hi_b[j]
            j += 1
        else:
            d, u, v = abs(w_b[j] - w_a[i]), lo_b[j], hi_b[j]
            i += 1
            j += 1
        acc_lo[u] += d
        acc_hi[v] += d
    return acc_lo + acc_hi


@njit(cache=True)
def shifted_csc_kernel(n, lo, hi, w, tau):  # noqa: ANN001, ANN201
    """``L - tau I`` in CSC form (sorted rows) from links sorted by ``(lo, hi)``.

    Column ``c`` holds the rows ``lo < c`` of the links ``(lo, c)`` in link order, the
    diagonal, then the rows ``hi > c`` of the links ``(c, hi)`` in link order.
    """
    m = len(w)
    below = np.zeros(n, np.int64)
    above = np.zeros(n, np.int64)
    deg_lo = np.zeros(n)
    deg_hi = np.zeros(n)
    for k in range(m):
        below[hi[k]] += 1
        above[lo[k]] += 1
        deg_lo[lo[k]] += w[k]
        deg_hi[hi[k]] += w[k]
    deg = deg_lo + deg_hi
    indptr = np.zeros(n + 1, np.int64)
    for c in range(n):
        indptr[c + 1] = indptr[c] + below[c] + 1 + above[c]
    indices = np.empty(indptr[n], np.int64)
    data = np.empty(indptr[n])
    fill_below = indptr[:-1].copy()
    fill_above = indptr[:-1] + below + 1
    for c in range(n):
        indices[indptr[c] + below[c]] = c
        data[indptr[c] + below[c]] = deg[c] - tau
    for k in range(m):
        u, v = lo[k], hi[k]
        indices[fill_below[v]] = u
        data[fill_below[v]] = -w[k]
        fill_below[v] += 1
        indices[fill_above[u]] = v
        data[fill_above[u]] = -w[k]
        fill_above[u] += 1
    return indptr, indices, data


def warm_up() -> None:
    """Compile (or load from numba's cache) the kernels."""
    lo = np.array([0, 0], np.int64)
    hi = np.array([1, 2], np.int64)
    w = np.array([1.0, 0.5])
    keys = lo * 3 + hi
    canonical_kernel(3, np.column_stack((lo, hi)), w)
    product_kernel(3, lo, hi, w, np.ones(3))
    change_kernel(3, keys, lo, hi, w, keys, lo, hi, w)
    shifted_csc_kernel(3, lo, hi, w, 0.1)
