"""Compiled ray casting of :mod:`tether.sensing.depth` (numba; imported only when used).

:func:`scan_kernel` walks each ray's samples the way
:func:`tether.sensing.depth._scan` evaluates them all: sample ``k`` of a ray from
``o`` along ``(dx, dy)`` is ``o + (dx, dy) * s[k]`` (the same product and sum, the
``cos``/``sin`` numpy's, passed in), its cell the floor; a sample is seen when it is
inside the grid and no earlier sample of its ray was blocked (occupied or outside),
so the walk stops at the first blocking sample (seen if it is an occupied cell). The
cells come out in the reference's order (ray by ray, sample by sample), so the scans
are the same arrays (tests compare them).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def scan_kernel(occupied, origins, dx, dy, s):  # noqa: ANN001, ANN201
    """Seen flat cells of every origin's rays, concatenated, and each origin's count.

    ``origins``: ``(g, 2)``; ``dx``, ``dy``: ``(g, R)`` ray directions; ``s``: ``(S,)``
    sample distances. Returns ``(cells, counts)`` with ``cells`` ordered by origin,
    ray, sample.
    """
    nx_, ny_ = occupied.shape
    g, n_rays = dx.shape
    out = np.empty(g * n_rays * len(s), np.int64)
    counts = np.zeros(g, np.int64)
    m = 0
    for i in range(g):
        ox = origins[i, 0]
        oy = origins[i, 1]
        start = m
        for r in range(n_rays):
            ux = dx[i, r]
            uy = dy[i, r]
            for k in range(len(s)):
                ix = int(math.floor(ox + ux * s[k]))
                iy = int(math.floor(oy + uy * s[k]))
                if ix < 0 or ix >= nx_ or iy < 0 or iy >= ny_:
                    break  # outside: blocks, not seen
                out[m] = ix * ny_ + iy
                m += 1
                if occupied[ix, iy]:
                    break  # the first hit is seen, nothing behind it
        counts[i] = m - start
    return out[:m], counts


def warm_up() -> None:
    """Compile (or load from numba's cache) the kernel on a 4 x 4 map."""
    occ = np.zeros((4, 4), dtype=bool)
    occ[3, 3] = True
    dx = np.ones((1, 2))
    scan_kernel(occ, np.full((1, 2), 0.5), dx, dx * 0.5, np.arange(0.0, 3.0, 0.5))
