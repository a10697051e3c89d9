"""Pairs within a range through a uniform cell grid (numba), for large teams.

:func:`pairs_within_grid_kernel` gives :func:`tether.graph.structure.pairs_within`'s
result -- every pair ``i < j`` with ``sum_d (q_i - q_j)_d^2 <= r^2`` in lexicographic
order -- by the cell-list method (Allen and Tildesley, *Computer Simulation of Liquids*,
Sec. 5.3.2): points are sorted (counting sort) by the cell of side ``r`` they lie in,
and each point is
tested against the points of its ``3^dim`` neighbouring cells only, ``O(n log n + m)``
for a team of bounded density. The distance test is the k-d tree's and
:func:`~tether.graph.kernels.pairs_within_kernel`'s (squares summed in coordinate
order against ``r * r``), so the pairs are the same (tests compare them).
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: cells are this much wider than the range, so two points within range are never
#: two cells apart whatever the rounding of their cell coordinates
CELL_SLACK = 1.0 + 1e-6


@njit(cache=True, inline="always")
def cell_order(key, n_cells):  # noqa: ANN001, ANN201
    """Counting sort of points by cell: ``(start, order)`` with the points of cell ``c``
    at ``order[start[c]:start[c + 1]]``, in their own order (stable), ``O(n + cells)``."""
    start = np.zeros(n_cells + 1, np.int64)
    for i in range(len(key)):
        start[key[i] + 1] += 1
    for c in range(n_cells):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    order = np.empty(len(key), np.int64)
    for i in range(len(key)):
        order[fill[key[i]]] = i
        fill[key[i]] += 1
    return start, order


@njit(cache=True)
def pairs_within_grid_kernel(q, r, ncell):  # noqa: ANN001, ANN201
    """Pairs within ``r`` of the points ``q`` (``(n, dim)``); ``ncell``: cells per axis.

    ``ncell`` comes from :func:`grid_shape` (whose product must fit in ``int64``).
    """
    n, dim = q.shape
    r2 = r * r
    side = r * CELL_SLACK
    lo = np.empty(dim)
    for d in range(dim):
        lo[d] = q[:, d].min()
    cell = np.empty((n, dim), np.int64)
    key = np.empty(n, np.int64)
    for i in range(n):
        k = 0
        for d in range(dim):
            c = min(max(int(np.floor((q[i, d] - lo[d]) / side)), 0), ncell[d] - 1)
            cell[i, d] = c
            k = k * ncell[d] + c
        key[i] = k
    n_cells = 1
    for d in range(dim):
        n_cells *= ncell[d]
    start, order = cell_order(key, n_cells)
    n_off = 3**dim
    cap = 8 * n + 8
    out = np.empty((cap, 2), np.int64)
    m = 0
    buf = np.empty(n, np.int64)
    for i in range(n):
        nb = 0
        for o in range(n_off):
            rest = o
            k = 0
            inside = True
            for d in range(dim):
                c = cell[i, d] + rest % 3 - 1
                rest //= 3
                if c < 0 or c >= ncell[d]:
                    inside = False
                    break
                k = k * ncell[d] + c
            if not inside:
                continue
            for e in range(start[k], start[k + 1]):
                j = order[e]
                if j <= i:
                    continue
                sq = 0.0
                for d in range(dim):
                    x = q[i, d] - q[j, d]
                    sq += x * x
                if sq <= r2:
                    f = nb  # insertion sort: neighbour lists are short
                    while f > 0 and buf[f - 1] > j:
                        buf[f] = buf[f - 1]
                        f -= 1
                    buf[f] = j
                    nb += 1
        if nb == 0:
            continue
        if m + nb > len(out):
            bigger = np.empty((2 * (m + nb), 2), np.int64)
            bigger[:m] = out[:m]
            out = bigger
        for e in range(nb):
            out[m, 0], out[m, 1] = i, buf[e]
            m += 1
    return out[:m].copy()


def grid_shape(q: np.ndarray, r: float) -> np.ndarray | None:
    """Cells per axis for :func:`pairs_within_grid_kernel`, or ``None`` if too many.

    ``None`` when the grid would have more than ``4 n + 64`` cells (a range small
    against the team's extent: mostly empty cells, where the k-d tree is faster); the
    caller keeps the k-d tree then.
    """
    if not (r > 0 and np.isfinite(r)) or len(q) == 0 or not np.isfinite(q).all():
        return None
    extent = q.max(axis=0) - q.min(axis=0)
    ncell = np.floor(extent / (r * CELL_SLACK)).astype(np.float64) + 1.0
    if float(np.prod(ncell)) > 4.0 * len(q) + 64.0:
        return None
    return ncell.astype(np.int64)


def warm_up() -> None:
    """Compile (or load from numba's cache) the kernel for 2-D and 3-D points."""
    for dim in (2, 3):
        q = np.eye(3, dim)
        pairs_within_grid_kernel(q, 1.5, grid_shape(q, 1.5))
