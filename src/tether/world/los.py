"""Line of sight on a boolean cell mask (cell coordinates).

Cell ``(ix, iy)`` covers ``[ix, ix + 1) x [iy, iy + 1)``. The mask may be the
true free space or a robot's *known* free space (unknown cells block), which
is how the recurrent-connectivity planner predicts links it can rely on.
Metric line of sight with a clearance on a world's occupancy grid is
:meth:`tether.world.grid.OccupancyGrid.segments_clear`; exact clearance from an
obstacle point set is :class:`tether.world.clearance.ObstacleIndex`.
"""

from __future__ import annotations

import numpy as np

from tether import jit

__all__ = ["segment_free"]


def segment_free(
    free: np.ndarray, a: np.ndarray, b: np.ndarray, step_cells: float = 0.5, chunk: int = 4096
) -> np.ndarray:
    """Boolean ``(k,)``: every sample of segment ``a[k] -> b[k]`` lies in a ``free`` cell.

    ``free`` is a 2-D or 3-D boolean mask; ``a`` and ``b`` are ``(k, dim)``
    points in continuous cell coordinates. Samples are ``step_cells`` apart
    from the lexicographically smaller end (plus the far end), so the answer
    is symmetric and does not depend on the other segments of the batch.
    Points outside the grid count as blocked. Cost ``O(k * length / step)``.
    """
    a = np.atleast_2d(np.asarray(a, dtype=float))
    b = np.atleast_2d(np.asarray(b, dtype=float))
    out = np.zeros(len(a), dtype=bool)
    if len(a) == 0:
        return out
    if jit.warm() and free.flags.c_contiguous:  # the same samples, compiled
        from tether.world.los_kernels import segment_free_kernel

        shape = np.asarray(free.shape, dtype=np.int64)
        return segment_free_kernel(free.reshape(-1), shape, np.ascontiguousarray(a),
                                   np.ascontiguousarray(b), float(step_cells))  # fmt: skip
    # canonical direction: the lexicographically smaller end first
    diff = b - a
    nonzero = diff != 0
    first = np.argmax(nonzero, axis=1)
    swap = nonzero.any(axis=1) & (diff[np.arange(len(a)), first] < 0)
    a, b = np.where(swap[:, None], b, a), np.where(swap[:, None], a, b)
    shape = np.asarray(free.shape)
    length = np.linalg.norm(b - a, axis=1)
    n_samples = int(np.ceil(length.max() / step_cells)) + 1
    k = np.arange(n_samples) * step_cells
    for lo in range(0, len(a), chunk):
        aa, bb, ll = a[lo : lo + chunk], b[lo : lo + chunk], length[lo : lo + chunk]
        frac = np.minimum(k[None, :] / np.maximum(ll, 1e-12)[:, None], 1.0)
        inside = np.ones(frac.shape, dtype=bool)
        index = []
        for d in range(free.ndim):
            p = aa[:, d, None] + frac * (bb[:, d] - aa[:, d])[:, None]
            i = np.floor(p).astype(np.intp)
            inside &= (i >= 0) & (i < shape[d])
            index.append(np.clip(i, 0, shape[d] - 1))
        ok = free[tuple(index)] & inside
        out[lo : lo + chunk] = ok.all(axis=1)
    return out
