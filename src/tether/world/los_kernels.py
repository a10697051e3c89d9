"""Compiled kernel of :func:`tether.world.los.segment_free` (numba; imported only when used)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def segment_free_kernel(free, shape, a, b, step_cells):  # noqa: ANN001, ANN201
    """Per segment: every sample lies in a ``free`` cell (the numpy version's samples).

    ``free`` is the raveled C-order mask of ``shape``. Each segment runs from its
    lexicographically smaller end; sample ``k`` is ``min(k * step / length, 1)`` of
    the way (the numpy version's later samples repeat the far end, so the loop stops
    there). A sample outside the grid blocks.
    """
    k_seg, dim = a.shape
    out = np.zeros(k_seg, np.bool_)
    lo = np.empty(dim)
    hi = np.empty(dim)
    for s in range(k_seg):
        swap = False
        for d in range(dim):
            if b[s, d] != a[s, d]:
                swap = b[s, d] - a[s, d] < 0
                break
        for d in range(dim):
            lo[d] = b[s, d] if swap else a[s, d]
            hi[d] = a[s, d] if swap else b[s, d]
        sq = 0.0
        for d in range(dim):
            sq += (hi[d] - lo[d]) * (hi[d] - lo[d])
        length = max(math.sqrt(sq), 1e-12)
        ok = True
        k = 0
        while True:
            frac = min(k * step_cells / length, 1.0)
            flat = 0
            for d in range(dim):
                c = int(math.floor(lo[d] + frac * (hi[d] - lo[d])))
                if c < 0 or c >= shape[d]:
                    ok = False
                    break
                flat = flat * shape[d] + c
            if not ok or not free[flat]:
                ok = False
                break
            if frac >= 1.0:
                break
            k += 1
        out[s] = ok
    return out
