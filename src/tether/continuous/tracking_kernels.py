"""Compiled kernel of :meth:`tether.continuous.tracking.PathSet.states` (numba, lazy).

Closest points of robots on their sampled paths, path by path, with the arithmetic of
the numpy version (same bits; ``tests/test_kernels.py``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tether.world.clearance_kernels import edot


@njit(cache=True, inline="always")
def _foot(q, r, pa, dseg, inv_len2, k, order, rel, off):  # noqa: ANN001, ANN202
    """``(t, |q_r - foot|)`` on segment ``k``, in the numpy version's arithmetic."""
    dim = q.shape[1]
    for c in range(dim):
        rel[c] = q[r, c] - pa[k, c]
    t = min(max(edot(rel, dseg[k], order) * inv_len2[k], 0.0), 1.0)
    for c in range(dim):
        off[c] = rel[c] - t * dseg[k, c]
    return t, math.sqrt(edot(off, off, order))


@njit(cache=True, inline="always")
def _skip_to(q, r, pa, chord_start, chord_end, k, hi, limit):  # noqa: ANN001, ANN202
    """First segment from ``k`` on that may come within ``limit`` of robot ``r``.

    A point of segment ``j >= k`` is at most ``chord_end[j] - chord_start[k]`` (the
    polyline's length in between) from the sample ``pa[k]``, so it is farther than
    ``limit`` from the robot while that is below ``|q_r - pa[k]| - limit``.
    """
    dim = q.shape[1]
    sq = 0.0
    for c in range(dim):
        sq += (q[r, c] - pa[k, c]) ** 2
    reach = math.sqrt(sq) - limit - 1e-9
    j = k
    while j < hi and chord_end[j] - chord_start[k] < reach:
        j += 1
    return j


@njit(cache=True)
def path_states_kernel(  # noqa: ANN201, PLR0913
    q, first, pa, dseg, inv_len2, sa, ds, ta, dta, ka, dka, lengths, speed, tie, order,
    chord_start, chord_end, hint,
):  # noqa: ANN001  # fmt: skip
    """Closest points of :meth:`tether.continuous.tracking.PathSet.states`, path by path.

    For robot ``r`` the segments ``first[r]:first[r + 1]`` of its path: the least
    distance, then among the segments within ``tie`` of it the largest arc length
    (the first such segment), in the numpy version's arithmetic (``order``:
    :func:`tether.world.clearance.einsum_order`). Runs of segments that cannot come
    that close are skipped (:func:`_skip_to`, from the cumulative chord lengths); the
    search starts from ``hint[r]`` (last call's segment, updated), which only speeds it
    up. Returns ``s_best``, ``point``, ``distance``, ``remaining``, ``velocity``,
    ``acceleration``.
    """
    r_count, dim = q.shape
    s_best = np.empty(r_count)
    point = np.empty((r_count, dim))
    dist_out = np.empty(r_count)
    remaining = np.empty(r_count)
    vel = np.empty((r_count, dim))
    acc = np.empty((r_count, dim))
    rel = np.empty(dim)
    off = np.empty(dim)
    for r in range(r_count):
        lo, hi = first[r], first[r + 1]
        best = np.inf
        if lo <= hint[r] < hi:
            best = _foot(q, r, pa, dseg, inv_len2, hint[r], order, rel, off)[1]
        k = lo
        while k < hi:  # the least distance
            j = _skip_to(q, r, pa, chord_start, chord_end, k, hi, best + tie)
            if j > k:
                k = j
                continue
            best = min(best, _foot(q, r, pa, dseg, inv_len2, k, order, rel, off)[1])
            k += 1
        s_max, pick, t_pick, d_pick = -np.inf, -1, 0.0, 0.0
        k = lo
        while k < hi:  # the largest arc length within tie of it
            j = _skip_to(q, r, pa, chord_start, chord_end, k, hi, best + tie)
            if j > k:
                k = j
                continue
            t, dk = _foot(q, r, pa, dseg, inv_len2, k, order, rel, off)
            if dk <= best + tie:
                s_foot = sa[k] + t * ds[k]
                if s_foot > s_max:
                    s_max, pick, t_pick, d_pick = s_foot, k, t, dk
            k += 1
        hint[r] = pick
        s_best[r] = s_max
        dist_out[r] = d_pick
        for c in range(dim):
            rel_c = q[r, c] - pa[pick, c]
            point[r, c] = q[r, c] - (rel_c - t_pick * dseg[pick, c])
        v = speed[r] * (1.0 if (lengths[r] - s_max) > 1e-9 else 0.0)
        remaining[r] = max(lengths[r] - s_max, 0.0)
        for c in range(dim):
            vel[r, c] = v * (ta[pick, c] + t_pick * dta[pick, c])
            acc[r, c] = (v * v) * (ka[pick, c] + t_pick * dka[pick, c])
    return s_best, point, dist_out, remaining, vel, acc
