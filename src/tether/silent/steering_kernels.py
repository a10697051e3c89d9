"""Compiled :func:`tether.silent.steering.constrained_steps` (numba), robot by robot.

Constraints (1) and (2) of Kerestecioglu and Cezayirli, "Connected Navigation of
Non-Communicating Mobile Agents" (Sec. IV), evaluated robustly for the sensor's error
bounds exactly as :func:`tether.silent.steering._pair_bounds` does, and the candidate
search of :func:`~tether.silent.steering.constrained_steps`; one pass per robot over its
own measurements instead of numpy arrays of ``sum_i (1 + deg_i) deg_i`` pairs. The
arithmetic is the reference's, term for term (norms summed in the same order, dot
products in ``np.einsum``'s order); ``arccos`` and ``cos`` come from the C library
instead of numpy's, so results agree to rounding (tests: 1e-12). Imported only when
:func:`tether.jit.enabled`.

Two exact short cuts (the steps are bit-identical with and without them): the
direction search skips candidates whose progress cannot beat the best one's, and a
pair whose bound is surely no smaller than the robot's current bound skips ``acos``
and ``cos`` (:func:`_bound`).

:func:`silent_step_kernel`: a whole :meth:`~tether.silent.strategy.SilentStrategy.step`
of a team on a waypoint path in free space in one call: the leader's carrot on its path
(:meth:`tether.paths.trajectory.Polyline.project`, then ``at``), :func:`team_steps_kernel`,
the kinematic integration and the leader's statistics. For 20 robots each of these is a
few microseconds of arithmetic behind tens of microseconds of Python calls. The
reference's arithmetic operation for operation: Python's ``min``/``max`` (the first
argument unless the second is strictly smaller/larger) and ``_clip`` (NaN kept); numpy's
``dot`` of two short vectors (``(point - a).dot(ab)``, ``gap.dot(gap)``, ``_norm``)
summed in coordinate order, as OpenBLAS's ``ddot`` sums fewer than 16 elements (its
scalar loop; tests compare bit for bit); ``bisect_right`` by a linear scan. So the
positions, velocities and the leader's progress and travel are the reference's bits.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tether.sensing.robots_kernels import _dot_rows, _unit_rows

#: margin on ``cos(phi)`` beyond which a branch of :func:`_bound` is taken without
#: ``acos`` (an angle error of at least 1e-9 rad, far above ``acos``'s rounding)
MARGIN = 1e-9


@njit(cache=True)
def _bound_exact(cos_phi, dist, d_m, r_err, ang, min_sep):  # noqa: ANN001, ANN202, PLR0913
    """:func:`~tether.silent.steering._pair_bounds` for one direction and one measurement."""
    phi = math.acos(min(max(cos_phi, -1.0), 1.0))
    worst = phi + ang
    half_pi = math.pi / 2
    if worst < half_pi:
        bound = (dist - r_err) * math.cos(min(worst, half_pi))  # constraint (2)
    else:
        bound = 0.5 * (d_m - dist)  # constraint (1)
    if min_sep > 0 and phi - ang < half_pi:
        bound = min(bound, 0.5 * (dist - r_err - min_sep))
    return max(bound, 0.0)


@njit(cache=True, inline="always")
def _bound(cos_phi, dist, d_m, r_err, ang, min_sep, sin_ang, cos_ang, b):  # noqa: ANN001, ANN202, PLR0913
    """:func:`_bound_exact`, or ``inf`` when the pair's bound is surely ``>= b``.

    ``min(b, _bound(...))`` is exactly ``min(b, _bound_exact(...))``: where ``cos(phi)``
    is more than :data:`MARGIN` from a branch's threshold (``worst < pi/2`` is
    ``cos(phi) > sin(ang)``, ``phi - ang < pi/2`` is ``cos(phi) > -sin(ang)``), the
    branch is known without ``acos``; constraint (1) is then computed as before, and
    constraint (2) is skipped when a lower bound of ``cos(phi + ang)`` (by the angle-sum
    formula, less :data:`MARGIN`) already puts it at or above ``b``.
    """
    c = min(max(cos_phi, -1.0), 1.0)
    if min_sep > 0:
        if c > -sin_ang + MARGIN:
            sep = 0.5 * (dist - r_err - min_sep)
        elif c < -sin_ang - MARGIN:
            sep = np.inf
        else:
            return _bound_exact(cos_phi, dist, d_m, r_err, ang, min_sep)
    else:
        sep = np.inf
    if c < sin_ang - MARGIN:  # constraint (1), surely
        return max(min(0.5 * (d_m - dist), sep), 0.0)
    if c > sin_ang + MARGIN and dist - r_err > 0:  # constraint (2), surely
        sin_phi = math.sqrt((1.0 - c) * (1.0 + c))
        low = (dist - r_err) * (c * cos_ang - sin_phi * sin_ang - MARGIN)
        if max(min(low, sep), 0.0) >= b:
            return np.inf
    return _bound_exact(cos_phi, dist, d_m, r_err, ang, min_sep)


@njit(cache=True)
def constrained_steps_kernel(  # noqa: ANN201, PLR0913
    desired, measured, indptr, d_max, r_err, ang, min_sep, max_step, search
):  # noqa: ANN001
    """Steps of :func:`~tether.silent.steering.constrained_steps` (measurements by observer).

    ``indptr``: robot ``i``'s measurements are ``measured[indptr[i]:indptr[i + 1]]``.
    """
    n, dim = desired.shape
    d_m = d_max - r_err
    sin_ang, cos_ang = math.sin(ang), math.cos(ang)
    m = len(measured)
    dist = np.empty(m)
    mu = np.empty((m, dim))
    for k in range(m):
        dist[k] = _unit_rows(measured, k, mu, k)
    steps = np.zeros((n, dim))
    ud = np.empty((1, dim))  # the desired direction (rows are passed by index, not as views)
    for i in range(n):
        length = _unit_rows(desired, i, ud, 0)
        lo, hi = indptr[i], indptr[i + 1]
        best_k, best_allowed, best_progress = -1, 0.0, -np.inf
        last = hi if search else lo
        for cand in range(lo - 1, last):  # lo - 1: the desired direction, then each robot
            u, iu = (ud, 0) if cand < lo else (mu, cand)
            dot = _dot_rows(u, iu, ud, 0)
            # pruning (search only): progress = allowed * dot with allowed >= 0 only
            # shrinking over k, so a candidate that cannot beat the best is skipped
            # exactly (ties keep the earlier one anyway); best_progress >= 0 after the
            # desired direction, so dot <= 0 can never win
            if (
                search
                and best_progress >= 0.0
                and (dot <= 0.0 or min(length, max_step) * dot <= best_progress)
            ):
                continue
            b = np.inf
            for k in range(lo, hi):
                cos_phi = _dot_rows(u, iu, mu, k)
                b = min(b, _bound(cos_phi, dist[k], d_m, r_err, ang, min_sep, sin_ang, cos_ang, b))
                if (
                    search
                    and best_progress >= 0.0
                    and min(min(length, b), max_step) * dot <= best_progress
                ):
                    break
            allowed = min(min(length, b), max_step)
            if not search:
                for c in range(dim):
                    steps[i, c] = u[iu, c] * allowed
                break
            progress = allowed * dot
            if progress > best_progress:  # ties keep the earlier candidate
                best_k, best_allowed, best_progress = cand, allowed, progress
        if search and best_progress > 0.0:
            u, iu = (ud, 0) if best_k < lo else (mu, best_k)
            for c in range(dim):
                steps[i, c] = u[iu, c] * best_allowed
    return steps


@njit(cache=True)
def desired_distance_kernel(measured, observer, n, gamma, d0_m):  # noqa: ANN001, ANN201
    """:func:`~tether.silent.steering.desired_steps` for cost (13): eq. (15) summed per robot.

    The same terms ``2 gamma (||x_k|| - d0) x_k / ||x_k||`` added in measurement order
    as ``np.add.at`` adds them, so the sums are bit-identical.
    """
    m, dim = measured.shape
    out = np.zeros((n, dim))
    u = np.empty((1, dim))
    scale = 2.0 * gamma
    for q in range(m):
        dist = _unit_rows(measured, q, u, 0)
        f = scale * (dist - d0_m)
        o = observer[q]
        for c in range(dim):
            out[o, c] += f * u[0, c]
    return out


@njit(cache=True)
def team_steps_kernel(  # noqa: ANN201, PLR0913
    measured, indptr, leader, leader_step, gamma, d0_m, d_max, r_err, ang, min_sep, max_step,
    search,
):  # noqa: ANN001  # fmt: skip
    """:func:`~tether.silent.steering.team_steps` for cost (13) in one call.

    The desired steps (15) summed per robot over its CSR row (the terms in measurement
    order, as :func:`desired_distance_kernel` and ``np.add.at`` add them), the leader's
    replaced by ``leader_step``, then :func:`constrained_steps_kernel`: the same values,
    bit for bit, as the three steps called one by one.
    """
    n = len(indptr) - 1
    dim = measured.shape[1]
    desired = np.zeros((n, dim))
    u = np.empty((1, dim))
    scale = 2.0 * gamma
    for i in range(n):
        for q in range(indptr[i], indptr[i + 1]):
            dist = _unit_rows(measured, q, u, 0)
            f = scale * (dist - d0_m)
            for c in range(dim):
                desired[i, c] += f * u[0, c]
    for c in range(dim):
        desired[leader, c] = leader_step[c]
    return constrained_steps_kernel(
        desired, measured, indptr, d_max, r_err, ang, min_sep, max_step, search
    )


@njit(cache=True, inline="always")
def _py_max(a, b):  # noqa: ANN001, ANN202
    """Python's ``max(a, b)``: ``a`` unless ``b > a``."""
    return b if b > a else a


@njit(cache=True, inline="always")
def _py_min(a, b):  # noqa: ANN001, ANN202
    """Python's ``min(a, b)``: ``a`` unless ``b < a``."""
    return b if b < a else a


@njit(cache=True, inline="always")
def _clip(x, lo, hi):  # noqa: ANN001, ANN202
    """:func:`tether.paths.trajectory._clip`: ``min(max(x, lo), hi)``, NaN kept."""
    return x if x != x else _py_min(_py_max(x, lo), hi)


@njit(cache=True)
def _at(points, seg, cum, seg_len, length, s_m, out):  # noqa: ANN001, ANN202, PLR0913
    """:meth:`~tether.paths.trajectory.Polyline.at` into ``out`` (``(dim,)``)."""
    s = _clip(s_m, 0.0, length)
    dim = points.shape[1]
    if len(points) == 1 or length == 0.0:
        for c in range(dim):
            out[c] = points[0, c]
        return
    k = 0  # bisect_right(cum, s) - 1: the number of arc lengths <= s, less one
    while k < len(cum) and not s < cum[k]:
        k += 1
    k = min(max(k - 1, 0), len(seg_len) - 1)
    frac = (s - cum[k]) / _py_max(seg_len[k], 1e-12)
    for c in range(dim):
        out[c] = points[k, c] + frac * seg[k, c]


@njit(cache=True)
def _project(points, seg, denom, cum, seg_len, length, point, s_min, window_m, gap):  # noqa: ANN001, ANN202, PLR0913
    """:meth:`~tether.paths.trajectory.Polyline.project` (``gap``: a ``(dim,)`` scratch)."""
    best_s, best_d = s_min, np.inf
    dim = len(point)
    for k in range(len(denom)):
        s0, s1 = cum[k], cum[k + 1]
        if s1 < s_min or s0 > s_min + window_m:
            continue
        if denom[k] == 0:
            t = 0.0
        else:
            dot = 0.0
            for c in range(dim):
                dot += (point[c] - points[k, c]) * seg[k, c]
            t = _clip(dot / denom[k], 0.0, 1.0)
        s = _clip(s0 + t * (s1 - s0), s_min, s_min + window_m)
        _at(points, seg, cum, seg_len, length, s, gap)
        d2 = 0.0
        for c in range(dim):
            g = gap[c] - point[c]
            d2 += g * g
        d = math.sqrt(d2)
        if d < best_d:
            best_s, best_d = s, d
    return best_s


@njit(cache=True)
def silent_step_kernel(  # noqa: ANN201, PLR0913
    positions, measured, indptr, leader, points, seg, denom, cum, seg_len, length, end,
    window_m, gamma, d0_m, d_max, r_err, ang, min_sep, search, progress_m, advance_m, dt_s,
    max_step,
):  # noqa: ANN001  # fmt: skip
    """One :meth:`~tether.silent.strategy.SilentStrategy.step` (cost (13), free space).

    ``points, seg, denom, cum, seg_len, length, end``: the path's waypoints, segment
    vectors, squared segment lengths, arc lengths, segment lengths, length and last
    point; ``progress_m`` the leader's progress so far, ``advance_m`` its speed times
    ``dt_s``, ``window_m`` the projection's window. Returns the new positions, the
    velocities, and ``(progress_m, wanted_m, moved_m, end_distance_m)``: the leader's
    new progress, the length of its wanted and of its allowed step, and its distance to
    the path's end after the step.
    """
    n, dim = positions.shape
    point = np.empty(dim)
    for c in range(dim):
        point[c] = positions[leader, c]
    scratch = np.empty(dim)
    s = _project(points, seg, denom, cum, seg_len, length, point, progress_m, window_m, scratch)
    progress_m = _py_max(progress_m, s)
    target = np.empty(dim)
    _at(points, seg, cum, seg_len, length, progress_m + advance_m, target)
    leader_step = np.empty(dim)
    for c in range(dim):
        leader_step[c] = target[c] - point[c]
    steps = team_steps_kernel(
        measured, indptr, leader, leader_step, gamma, d0_m, d_max, r_err, ang, min_sep,
        max_step, search,
    )  # fmt: skip
    wanted2 = 0.0
    moved2 = 0.0
    for c in range(dim):
        wanted2 += leader_step[c] * leader_step[c]
        moved2 += steps[leader, c] * steps[leader, c]
    new_positions = np.empty((n, dim))
    velocities = np.empty((n, dim))
    for i in range(n):
        for c in range(dim):
            new_positions[i, c] = positions[i, c] + steps[i, c]
            velocities[i, c] = steps[i, c] / dt_s
    gap2 = 0.0
    for c in range(dim):
        g = new_positions[leader, c] - end[c]
        gap2 += g * g
    stats = (progress_m, math.sqrt(wanted2), math.sqrt(moved2), math.sqrt(gap2))
    return new_positions, velocities, stats


def warm_up() -> None:
    """Compile (or load from numba's cache) the kernel for 2-D and 3-D teams."""
    for dim in (2, 3):
        desired = np.ones((2, dim))
        measured = np.eye(2, dim)
        indptr = np.array([0, 1, 2], np.int64)
        for search in (False, True):
            constrained_steps_kernel(desired, measured, indptr, 15.0, 0.4, 0.2, 0.5, np.inf, search)
        desired_distance_kernel(measured, indptr[:-1].copy(), 2, 0.2, 8.0)
        for search in (False, True):
            team_steps_kernel(measured, indptr, 0, desired[0], 0.2, 8.0, 15.0, 0.4, 0.2, 0.5,
                              np.inf, search)  # fmt: skip
    for dim in (2, 3):  # the whole step (silent_step_kernel)
        pos = np.eye(2, dim) * 3.0
        measured = np.concatenate([pos[1:] - pos[:1], pos[:1] - pos[1:]])
        indptr = np.array([0, 1, 2], np.int64)
        pts = np.array([np.zeros(dim), np.ones(dim) * 10.0])
        seg = np.diff(pts, axis=0)
        denom = np.array([float(seg[0] @ seg[0])])
        seg_len = np.sqrt(denom)
        cum = np.array([0.0, seg_len[0]])
        for search in (False, True):
            silent_step_kernel(pos, measured, indptr, 0, pts, seg, denom, cum, seg_len,
                               float(cum[-1]), pts[-1], 30.0, 0.2, 8.0, 15.0, 0.4, 0.2, 0.5,
                               search, 0.0, 1.0, 1.0, np.inf)  # fmt: skip
