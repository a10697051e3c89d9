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

__all__ = ["segment_free"]


def segment_free(
    free: np.ndarray, a: np.ndarray, b: np.ndarray, step_cells: float = 0.5, chunk: int = 4096
) -> np.ndarray:
    """Boolean ``(k,)``: every sample of segment ``a[k] -> b[k]`` lies in ``free``.

    Samples are ``step_cells`` apart from the lexicographically smaller end
    (plus the far end), so the answer is symmetric and independent of the
    batch. Points outside the grid count as blocked.
    """
    a = np.atleast_2d(np.asarray(a, dtype=float))
    b = np.atleast_2d(np.asarray(b, dtype=float))
    out = np.zeros(len(a), dtype=bool)
    if len(a) == 0:
        return out
    # canonical direction and absolute sample spacing: the answer for a segment
    # does not depend on its orientation or on the other segments of the batch
    swap = (a[:, 0] > b[:, 0]) | ((a[:, 0] == b[:, 0]) & (a[:, 1] > b[:, 1]))
    a, b = np.where(swap[:, None], b, a), np.where(swap[:, None], a, b)
    nx_, ny_ = free.shape
    length = np.linalg.norm(b - a, axis=1)
    n_samples = int(np.ceil(length.max() / step_cells)) + 1
    k = np.arange(n_samples) * step_cells
    for lo in range(0, len(a), chunk):
        aa, bb, ll = a[lo : lo + chunk], b[lo : lo + chunk], length[lo : lo + chunk]
        frac = np.minimum(k[None, :] / np.maximum(ll, 1e-12)[:, None], 1.0)
        px = aa[:, 0, None] + frac * (bb[:, 0] - aa[:, 0])[:, None]
        py = aa[:, 1, None] + frac * (bb[:, 1] - aa[:, 1])[:, None]
        ix = np.floor(px).astype(np.intp)
        iy = np.floor(py).astype(np.intp)
        inside = (ix >= 0) & (ix < nx_) & (iy >= 0) & (iy < ny_)
        ok = free[np.clip(ix, 0, nx_ - 1), np.clip(iy, 0, ny_ - 1)] & inside
        out[lo : lo + chunk] = ok.all(axis=1)
    return out
