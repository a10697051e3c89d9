"""Compiled search of the robot pairs within a range (numba, lazy).

:func:`pairs_in_range` finds the pairs of App. A's weighted graph (the robots within
``Rs``) for :mod:`tether.continuous.connectivity.kernels`; :func:`pairs_below` filters given pairs.
The same pairs, in lexicographic order, as the numpy reference
(:func:`tether.graph.structure.pairs_within` followed by the distance test of
:func:`tether.continuous.connectivity.weights.compute_weights`): ``tests/test_pairs_in_range.py``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tether.graph.grid_kernels import cell_order

#: below this many robots the pairs are found by testing all of them
BRUTE_MAX_N = 128


@njit(cache=True, inline="always")
def row_norm(x):  # noqa: ANN001, ANN202
    """``numpy.linalg.norm`` of a short row: ``sqrt`` of the squares summed in order."""
    acc = 0.0
    for d in range(x.shape[0]):
        acc += x[d] * x[d]
    return math.sqrt(acc)


@njit(cache=True)
def pairs_in_range(q, r):  # noqa: ANN001, ANN201
    """All pairs ``(i, j)``, ``i < j``, with ``||q_i - q_j|| < r``, in lexicographic order.

    All pairs are tested below ``BRUTE_MAX_N`` robots; above, robots are bucketed in
    cubes of side ``r`` and each robot's partners sorted: the cubes in one array
    (:func:`_pairs_dense_cells`, ``O(n + m)``) when there are at most ``4 n + 1024``
    of them, else sorted cube codes with a binary search for the neighbouring cubes,
    ``O(n log n + m)``. The cell list of Allen and Tildesley, *Computer Simulation of
    Liquids*, Sec. 5.3.2.
    """
    n, dim = q.shape
    if n <= BRUTE_MAX_N:  # row_norm(diff) < r, the root taken only near r (as _pairs_dense_cells)
        # room for every pair: an array that may be replaced inside the loop costs a
        # reference count per pair (2-3x the loop)
        every = np.empty((max(n * (n - 1) // 2, 1), 2), np.int64)
        m = 0
        surely_in, surely_out = r * r * (1.0 - 1e-14), r * r * (1.0 + 1e-14)
        for i in range(n):
            for j in range(i + 1, n):
                acc = 0.0
                for d in range(dim):
                    x = q[i, d] - q[j, d]
                    acc += x * x
                if acc < surely_in or (acc <= surely_out and math.sqrt(acc) < r):
                    every[m, 0], every[m, 1] = i, j
                    m += 1
        return every[:m].copy()
    cap = 16 * n + 16
    out = np.empty((cap, 2), np.int64)
    m = 0
    diff = np.empty(dim)
    lo = np.empty(dim)
    for d in range(dim):
        lo[d] = q[:, d].min()
    cell = np.empty((n, dim), np.int64)
    size = np.ones(dim, np.int64)
    for k in range(n):
        for d in range(dim):
            cell[k, d] = int((q[k, d] - lo[d]) / r)
            size[d] = max(size[d], cell[k, d] + 3)
    code = np.zeros(n, np.int64)
    for k in range(n):
        c = 0
        for d in range(dim):
            c = c * size[d] + cell[k, d] + 1
        code[k] = c
    n_cells = 1
    for d in range(dim):
        n_cells *= size[d]
        if n_cells > 4 * n + 1024:
            break
    if n_cells <= 4 * n + 1024:
        return _pairs_dense_cells(q, r, code, size, n_cells, out)
    order = np.argsort(code, kind="mergesort")
    sorted_code = code[order]
    partners = np.empty(n, np.int64)
    offs = np.empty(dim, np.int64)
    for i in range(n):
        cnt = 0
        for nb in range(3**dim):
            rest = nb
            c = 0
            for d in range(dim):
                offs[d] = rest % 3 - 1
                rest //= 3
            for d in range(dim):
                c = c * size[d] + cell[i, d] + 1 + offs[d]
            first = np.searchsorted(sorted_code, c)
            while first < n and sorted_code[first] == c:
                j = order[first]
                first += 1
                if j <= i:
                    continue
                for d in range(dim):
                    diff[d] = q[i, d] - q[j, d]
                if row_norm(diff) < r:
                    partners[cnt] = j
                    cnt += 1
        partners[:cnt].sort()
        out, m = _append(out, m, i, partners, cnt)
    return out[:m].copy()


@njit(cache=True)
def _pairs_dense_cells(q, r, code, size, n_cells, out):  # noqa: ANN001, ANN202, PLR0913
    """:func:`pairs_in_range`'s cube search with every cube in one array (counting sort).

    The cube codes carry a margin of one cube on each side, so the ``3^dim``
    neighbours of a robot's cube are its code plus fixed offsets, and a cube's robots
    are one slice; the same cubes, distance test and order as the binary search.
    """
    n, dim = q.shape
    start, order = cell_order(code, n_cells)
    n_nb = 3**dim
    shift = np.zeros(n_nb, np.int64)
    for nb in range(n_nb):
        rest = nb
        c = 0
        for d in range(dim):
            c = c * size[d] + rest % 3 - 1
            rest //= 3
        shift[nb] = c
    partners = np.empty(n, np.int64)
    # sqrt(s) < r, decided without the square root away from r * r (both roundings are
    # within a relative 2^-52 of the exact values): the same pairs as row_norm(diff) < r
    surely_in = r * r * (1.0 - 1e-14)
    surely_out = r * r * (1.0 + 1e-14)
    m = 0
    for i in range(n):
        cnt = 0
        for nb in range(n_nb):
            c = code[i] + shift[nb]
            for e in range(start[c], start[c + 1]):
                j = order[e]
                if j <= i:
                    continue
                acc = 0.0
                for d in range(dim):
                    x = q[i, d] - q[j, d]
                    acc += x * x
                if acc > surely_out or (acc >= surely_in and not math.sqrt(acc) < r):
                    continue
                f = cnt  # insertion sort: a robot has few partners
                while f > 0 and partners[f - 1] > j:
                    partners[f] = partners[f - 1]
                    f -= 1
                partners[f] = j
                cnt += 1
        out, m = _append(out, m, i, partners, cnt)
    return out[:m].copy()


@njit(cache=True)
def _grow(out):  # noqa: ANN001, ANN202
    bigger = np.empty((2 * len(out), 2), np.int64)
    bigger[: len(out)] = out
    return bigger


@njit(cache=True)
def _append(out, m, i, partners, cnt):  # noqa: ANN001, ANN202
    """Rows ``(i, partners[k])`` for ``k < cnt`` after row ``m`` of ``out`` (grown as needed)."""
    while m + cnt > len(out):
        out = _grow(out)
    for k in range(cnt):
        out[m, 0], out[m, 1] = i, partners[k]
        m += 1
    return out, m


@njit(cache=True)
def pairs_below(q, pairs, r):  # noqa: ANN001, ANN201
    """The given pairs with ``||q_i - q_j|| < r`` (order kept)."""
    dim = q.shape[1]
    keep = np.zeros(len(pairs), np.bool_)
    diff = np.empty(dim)
    for k in range(len(pairs)):
        for d in range(dim):
            diff[d] = q[pairs[k, 0], d] - q[pairs[k, 1], d]
        keep[k] = row_norm(diff) < r
    return pairs[keep].copy()
