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

__all__ = ["cells_crossed", "segment_free"]

_NO_FIELD = np.zeros(0)


def segment_free(
    free: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    step_cells: float = 0.5,
    chunk: int = 4096,
    field: np.ndarray | None = None,
    field_to_cells: float = 1.0,
) -> np.ndarray:
    """Boolean ``(k,)``: every sample of segment ``a[k] -> b[k]`` lies in a ``free`` cell.

    ``free`` is a 2-D or 3-D boolean mask; ``a`` and ``b`` are ``(k, dim)``
    points in continuous cell coordinates. Samples are ``step_cells`` apart
    from the lexicographically smaller end (plus the far end), so the answer
    is symmetric and does not depend on the other segments of the batch.
    Points outside the grid count as blocked. Cost ``O(k * length / step)``.

    ``field`` (the mask's shape): distance from each free cell's centre to the nearest
    blocked cell's centre, in units of ``1 / field_to_cells`` cells (a grid's distance
    field in metres for its free cells). The compiled path then skips samples it
    proves free (the same answer, fewer reads); the reference ignores it.
    """
    a = np.atleast_2d(np.asarray(a, dtype=float))
    b = np.atleast_2d(np.asarray(b, dtype=float))
    out = np.zeros(len(a), dtype=bool)
    if len(a) == 0:
        return out
    if jit.warm() and free.flags.c_contiguous:  # the same samples, compiled
        from tether.world.los_kernels import segment_free_kernel

        shape = np.asarray(free.shape, dtype=np.int64)
        flat = _NO_FIELD if field is None else field.reshape(-1)
        return segment_free_kernel(free.reshape(-1), shape, np.ascontiguousarray(a),
                                   np.ascontiguousarray(b), float(step_cells), flat,
                                   float(field_to_cells))  # fmt: skip
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


def cells_crossed(
    blocked: np.ndarray, a: np.ndarray, b: np.ndarray, chunk: int = 2048
) -> np.ndarray:
    """Int ``(k,)``: how many ``blocked`` cells segment ``a[k] -> b[k]`` passes through.

    Exact on a 2-D mask: a cell counts when the open segment crosses its interior
    (touching a corner or running along an edge between two cells does not
    enter a cell the segment does not otherwise enter); the cells holding the
    end points count too. Cells outside the grid count as blocked. The segment
    is cut at every grid line it crosses and each piece of positive length lies
    in one cell, so the count is symmetric in ``a`` and ``b``.
    """
    a = np.atleast_2d(np.asarray(a, dtype=float))
    b = np.atleast_2d(np.asarray(b, dtype=float))
    if blocked.ndim != 2 or a.shape[1] != 2:
        raise ValueError("cells_crossed works on 2-D masks")
    out = np.zeros(len(a), dtype=np.int64)
    shape = np.asarray(blocked.shape)
    for lo in range(0, len(a), chunk):
        aa, bb = a[lo : lo + chunk], b[lo : lo + chunk]
        d = bb - aa
        ts = [np.zeros((len(aa), 1)), np.ones((len(aa), 1))]
        for ax in range(2):
            first = np.floor(np.minimum(aa[:, ax], bb[:, ax])) + 1
            last = np.ceil(np.maximum(aa[:, ax], bb[:, ax])) - 1
            count = np.maximum(last - first + 1, 0).astype(np.intp)
            width = int(count.max(initial=0))
            if width == 0:
                continue
            m = first[:, None] + np.arange(width)[None, :]
            with np.errstate(divide="ignore", invalid="ignore"):
                t = (m - aa[:, ax, None]) / d[:, ax, None]
            ts.append(np.where(np.arange(width)[None, :] < count[:, None], t, 1.0))
        t = np.sort(np.clip(np.hstack(ts), 0.0, 1.0), axis=1)
        mid = 0.5 * (t[:, 1:] + t[:, :-1])
        piece = (t[:, 1:] - t[:, :-1]) > 1e-12
        if not piece.any(axis=1).all():  # a point segment lies in the cell of its point
            piece[~piece.any(axis=1), 0] = True
        cell = np.floor(aa[:, None, :] + mid[..., None] * d[:, None, :]).astype(np.intp)
        inside = ((cell >= 0) & (cell < shape)).all(axis=2)
        cx = np.clip(cell[..., 0], 0, shape[0] - 1)
        cy = np.clip(cell[..., 1], 0, shape[1] - 1)
        wall = ~inside | blocked[cx, cy]
        out[lo : lo + chunk] = (wall & piece).sum(axis=1)
    return out
