"""Compiled kernel of :meth:`tether.continuous.exploration.tracking.PathSet.states` (numba, lazy).

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
    ``limit`` from the robot while that is below ``|q_r - pa[k]| - limit``. That test
    is monotone in ``j`` (``chord_end`` never decreases), so the first ``j`` failing it
    (or ``hi``) is found by bisection: the same ``j`` a scan finds.
    """
    dim = q.shape[1]
    sq = 0.0
    for c in range(dim):
        sq += (q[r, c] - pa[k, c]) ** 2
    reach = math.sqrt(sq) - limit - 1e-9
    base = chord_start[k]
    if not (k < hi and chord_end[k] - base < reach):
        return k
    lo, top = k, hi  # the test holds at lo; the answer is in (lo, top]
    while top - lo > 1:
        mid = (lo + top) // 2
        if chord_end[mid] - base < reach:
            lo = mid
        else:
            top = mid
    return top


@njit(cache=True)
def path_states_kernel(  # noqa: ANN201, PLR0913
    q, first, pa, dseg, inv_len2, sa, ds, ta, dta, ka, dka, lengths, speed, tie, order,
    chord_start, chord_end, hint,
):  # noqa: ANN001  # fmt: skip
    """Closest points of :meth:`tether.continuous.exploration.tracking.PathSet.states`,
    path by path.

    For robot ``r`` the segments ``first[r]:first[r + 1]`` of its path: the least
    distance, then among the segments within ``tie`` of it the largest arc length
    (the first such segment), in the numpy version's arithmetic (``order``:
    :func:`tether.world.clearance.einsum_order`). Runs of segments that cannot come
    that close are skipped (:func:`_skip_to`, from the cumulative chord lengths); the
    search starts from ``hint[r]`` (last call's segment, updated), which only speeds it
    up. Returns ``s_best``, ``point``, ``distance``, ``remaining``, ``velocity``,
    ``acceleration`` and the path's unit tangent and ``d2p/ds2`` at the closest points
    (velocity and acceleration are ``v`` and ``v^2`` times them).
    """
    r_count, dim = q.shape
    s_best = np.empty(r_count)
    point = np.empty((r_count, dim))
    dist_out = np.empty(r_count)
    remaining = np.empty(r_count)
    vel = np.empty((r_count, dim))
    acc = np.empty((r_count, dim))
    tan = np.empty((r_count, dim))
    kap = np.empty((r_count, dim))
    rel = np.empty(dim)
    off = np.empty(dim)
    most = 0
    for r in range(r_count):
        most = max(most, first[r + 1] - first[r])
    cand_k = np.empty(most, np.int64)  # segments within tie of the least distance so far
    cand_t = np.empty(most)
    cand_d = np.empty(most)
    for r in range(r_count):
        lo, hi = first[r], first[r + 1]
        best = np.inf
        if lo <= hint[r] < hi:
            best = _foot(q, r, pa, dseg, inv_len2, hint[r], order, rel, off)[1]
        # one pass: the least distance, and every segment within tie of the least so far
        # (it only shrinks, and the skipping is exact, so no segment within tie of the
        # final least is skipped or left out); then, in segment order, the largest arc
        # length among those within tie of the final least (the first of equals)
        count = 0
        k = lo
        while k < hi:
            j = _skip_to(q, r, pa, chord_start, chord_end, k, hi, best + tie)
            if j > k:
                k = j
                continue
            t, dk = _foot(q, r, pa, dseg, inv_len2, k, order, rel, off)
            best = min(best, dk)
            if dk <= best + tie:
                cand_k[count], cand_t[count], cand_d[count] = k, t, dk
                count += 1
            k += 1
        s_max, pick, t_pick, d_pick = -np.inf, -1, 0.0, 0.0
        for c_i in range(count):
            dk = cand_d[c_i]
            if dk <= best + tie:
                k, t = cand_k[c_i], cand_t[c_i]
                s_foot = sa[k] + t * ds[k]
                if s_foot > s_max:
                    s_max, pick, t_pick, d_pick = s_foot, k, t, dk
        hint[r] = pick
        s_best[r] = s_max
        dist_out[r] = d_pick
        for c in range(dim):
            rel_c = q[r, c] - pa[pick, c]
            point[r, c] = q[r, c] - (rel_c - t_pick * dseg[pick, c])
        v = speed[r] * (1.0 if (lengths[r] - s_max) > 1e-9 else 0.0)
        remaining[r] = max(lengths[r] - s_max, 0.0)
        for c in range(dim):
            tan[r, c] = ta[pick, c] + t_pick * dta[pick, c]
            kap[r, c] = ka[pick, c] + t_pick * dka[pick, c]
            vel[r, c] = v * tan[r, c]
            acc[r, c] = (v * v) * kap[r, c]
    return s_best, point, dist_out, remaining, vel, acc, tan, kap


@njit(cache=True)
def traveling_kernel(  # noqa: ANN201, PLR0913
    q, v, f_lambda, trav, secondary, lambda_hat, held, targets, path, v_cruise, tie, order,
    kp, kv, mass, damping, max_force, sigma, rz, kz, anchor_max,
):  # noqa: ANN001  # fmt: skip
    """``f_i`` of Algorithm 2 as :func:`tether.continuous.exploration.motion.traveling_forces`.

    ``trav``: the robots with a path (``path`` is their
    :meth:`~tether.continuous.exploration.tracking.PathSet.kernel_args`), ``secondary`` which of
    them are secondaries; ``held``: the anchored robots and ``targets`` their targets.
    Eq. (3) saturated, ``rho(Theta(f_lambda, f_travel), Lambda_hat, sigma)`` for the
    secondaries and ``f_anchor`` (eq. (7), saturated at ``anchor_max``), each in the numpy
    version's arithmetic.
    """
    n, dim = q.shape
    f = np.zeros((n, dim))
    r_count = len(trav)
    if r_count:
        first, pa, dseg, inv_len2, sa, ds, ta, dta, ka, dka, lengths, cs, ce, hint = path
        qt = np.empty((r_count, dim))
        for r in range(r_count):
            qt[r] = q[trav[r]]
        speed = np.full(r_count, v_cruise)
        _, point, _, _, vel, acc, _, _ = path_states_kernel(
            qt, first, pa, dseg, inv_len2, sa, ds, ta, dta, ka, dka, lengths, speed, tie, order,
            cs, ce, hint,
        )  # fmt: skip
        ft = np.empty(dim)
        for r in range(r_count):
            i = trav[r]
            for c in range(dim):
                ft[c] = (mass * acc[r, c] + damping * vel[r, c]) + kv * (vel[r, c] - v[i, c]) \
                    + kp * (point[r, c] - q[i, c])  # fmt: skip
            if np.isfinite(max_force):
                sq = 0.0
                for c in range(dim):
                    sq += ft[c] * ft[c]
                cap = min(1.0, max_force / max(math.sqrt(sq), 1e-300))
                for c in range(dim):
                    ft[c] = ft[c] * cap
            scale = 1.0
            if secondary[r]:
                nx, ny = 0.0, 0.0
                for c in range(dim):
                    nx += f_lambda[i, c] * f_lambda[i, c]
                    ny += ft[c] * ft[c]
                nx, ny = math.sqrt(nx), math.sqrt(ny)
                ok = nx > 0 and ny > 0
                cos = edot(f_lambda[i], ft, order) / (nx * ny if ok else 1.0)
                theta = 0.5 * (1.0 + min(max(cos, -1.0), 1.0)) if ok else 1.0
                x = min(max(theta, 0.0), 1.0)
                y = min(max(lambda_hat[i], 0.0), 1.0)
                scale = (1 - x) * y**sigma + x * (1 - (1 - y) ** sigma)
            for c in range(dim):
                f[i, c] = scale * ft[c]
    for k in range(len(held)):
        i = held[k]
        sq = 0.0
        for c in range(dim):
            sq += (q[i, c] - targets[k, c]) ** 2
        dist = math.sqrt(sq)
        mag = kz * math.tan(min(dist, rz) * np.pi / (2 * rz)) if dist < rz else np.nan
        if np.isfinite(anchor_max):  # saturated (anchor_force)
            mag = min(mag, anchor_max) if dist < rz else anchor_max
        den = max(dist, 1e-300)
        for c in range(dim):
            f[i, c] = -mag * ((q[i, c] - targets[k, c]) / den)
    return f


def warm_up() -> None:
    """Compile (or load) :func:`path_states_kernel` on one robot and a one-segment path."""
    q = np.array([[0.0, 0.0, 1.0]])
    first = np.array([0, 1], dtype=np.int64)
    seg = np.ones((1, 3))
    one = np.ones(1)
    path_states_kernel(q, first, seg, seg, one, one, one, seg, seg, seg, seg, one, one, 1e-6, 1,
                       one.copy(), one.copy() + 1, np.full(1, -1))  # fmt: skip
