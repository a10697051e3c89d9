"""Compiled min-plus relaxation of APX's shared Steiner DP (numba; imported only when used).

:func:`relax_kernel` is :func:`tether.recurrent.planning.apx._relax` --
``P[s, v] = min(min_u g[s, u] + d(u, v), cap)`` -- on the same small integers (hop
counts clipped at ``cap``, sums below ``3 cap``, exact in any order), with one row of
``d`` read per ``u`` instead of a ``(rows, n, n)`` block of sums; a ``u`` with
``g[s, u] >= cap`` cannot bring a value below the clip and is skipped.
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


def warm_up() -> None:
    """Compile (or load from numba's cache) the kernel for the DP's two dtypes."""
    for dtype in (np.int16, np.int32):
        d = np.array([[0, 1], [1, 0]], dtype=dtype)
        relax_kernel(d, d, 3)
