"""Compiled min-plus relaxation of APX's shared Steiner DP (numba; imported only when used).

:func:`relax_kernel` is :func:`tether.recurrent.planning.apx._relax` --
``P[s, v] = min(min_u g[s, u] + d(u, v), cap)`` -- on the same small integers (hop
counts clipped at ``cap``, sums below ``3 cap``, exact in any order), with one row of
``d`` read per ``u`` instead of a ``(rows, n, n)`` block of sums; a ``u`` with
``g[s, u] >= cap`` cannot bring a value below the clip and is skipped.

:func:`relax_graph_kernel` gives the same integers when ``d`` is the (clipped) hop
distance of a unit-cost graph, as in APX: ``min_u g[u] + d(u, v)`` is then a
breadth-first search from every vertex at once, each starting at its label ``g[u]``
(Dial's buckets, one per hop count below ``cap``), ``O(cap n + m)`` per row instead
of ``O(n^2)``.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def relax_kernel(g, dist, cap):  # noqa: ANN001, ANN201
    """``min(min_u g[s, u] + dist[u, v], cap)`` per row ``s`` of ``g``, in ``g``'s dtype."""
    rows, n = g.shape
    out = np.empty_like(g)
    best = np.empty(n, np.int64)
    for s in range(rows):
        best[:] = cap
        for u in range(n):
            gu = np.int64(g[s, u])
            if gu >= cap:
                continue
            for v in range(n):
                val = gu + dist[u, v]
                if val < best[v]:
                    best[v] = val
        for v in range(n):
            out[s, v] = best[v]
    return out


@njit(cache=True)
def relax_graph_kernel(g, indptr, indices, cap):  # noqa: ANN001, ANN201
    """``min(min_u g[s, u] + hops(u, v), cap)`` per row ``s``, on the graph ``(indptr, indices)``.

    Level by level: every vertex whose label is ``L`` when level ``L`` is reached is
    final (labels only fall to ``L + 1`` from level ``L``) and offers ``L + 1`` to its
    neighbours.
    """
    rows, n = g.shape
    out = np.empty_like(g)
    lab = np.empty(n, np.int64)
    for s in range(rows):
        for v in range(n):
            lab[v] = min(np.int64(g[s, v]), cap)
        for level in range(cap - 1):
            for u in range(n):
                if lab[u] != level:
                    continue
                for e in range(indptr[u], indptr[u + 1]):
                    w = indices[e]
                    if lab[w] > level + 1:
                        lab[w] = level + 1
        for v in range(n):
            out[s, v] = lab[v]
    return out


def warm_up() -> None:
    """Compile (or load from numba's cache) the kernel for the DP's two dtypes."""
    for dtype in (np.int16, np.int32):
        d = np.array([[0, 1], [1, 0]], dtype=dtype)
        relax_kernel(d, d, 3)
        relax_graph_kernel(d, np.array([0, 1, 2]), np.array([1, 0]), 3)
