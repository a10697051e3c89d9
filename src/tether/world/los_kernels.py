"""Compiled kernel of :func:`tether.world.los.segment_free` (numba; imported only when used)."""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def segment_free_kernel(free, shape, a, b, step_cells, field, to_cells):  # noqa: ANN001, ANN201
    """Per segment: every sample lies in a ``free`` cell (the numpy version's samples).

    ``free`` is the raveled C-order mask of ``shape``. Each segment runs from its
    lexicographically smaller end; sample ``k`` is ``min(k * step / length, 1)`` of
    the way (the numpy version's later samples repeat the far end, so the loop stops
    there). A sample outside the grid blocks.

    ``field`` (raveled like ``free``, or empty): the distance from each free cell's
    centre to the nearest blocked cell's centre, times ``1 / to_cells`` (a grid's
    distance field in metres with ``to_cells = 1 / resolution``). When a segment lies
    inside the grid, a free sample whose cell is ``D`` cells from a blocked one proves
    every later sample less than ``D - sqrt(dim)`` cells away free (their cells'
    centres are nearer than ``D`` to its centre), so those are not read: the same
    answer with fewer reads.
    """
    k_seg, dim = a.shape
    out = np.zeros(k_seg, np.bool_)
    lo = np.empty(dim)
    hi = np.empty(dim)
    root = math.sqrt(dim)
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
        skip = len(field) > 0
        for d in range(dim):  # well inside the grid: every sample is (rounding included)
            if not (min(lo[d], hi[d]) >= 1e-6 and max(lo[d], hi[d]) <= shape[d] - 1e-6):
                skip = False
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
            if skip:  # samples k + 1 .. k + m are proven free
                reach = (field[flat] * to_cells - root - 1e-6) / step_cells
                if reach >= 2.0:
                    if reach > 1e9:
                        reach = 1e9
                    k += int(reach)
            k += 1
        out[s] = ok
    return out


def warm_up() -> None:
    """Compile (or load) :func:`segment_free_kernel` on 2-D and 3-D grids, with and without
    a clearance field."""
    for mask in (np.ones((4, 4), dtype=bool), np.ones((4, 4, 4), dtype=bool)):
        shape = np.asarray(mask.shape, dtype=np.int64)
        a = np.full((1, mask.ndim), 0.5)
        for field in (np.zeros(0), np.ones(mask.size)):
            segment_free_kernel(mask.reshape(-1), shape, a, a + 1.0, 0.5, field, 1.0)
