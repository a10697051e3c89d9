"""One compiled call for a whole ``silent`` step of a small team (numba).

:meth:`tether.silent.strategy.SilentStrategy.step` on a waypoint path in free space (no
obstacles, no bounds) is, per step: the leader's carrot on its path
(:meth:`tether.paths.trajectory.Polyline.project`, then ``at``), the Local Steering
Strategy for the team (Kerestecioglu and Cezayirli, "Connected Navigation of
Non-Communicating Mobile Agents", Sec. IV: :func:`~tether.silent.steering_kernels.
team_steps_kernel`), the kinematic integration and the leader's bookkeeping. For 20
robots each of these is a few microseconds of arithmetic behind tens of microseconds
of Python calls; :func:`silent_step_kernel` does them in one call with the reference's
arithmetic, operation for operation:

* Python's ``min``/``max`` (the first argument unless the second is strictly
  smaller/larger, :func:`_py_min`, :func:`_py_max`) and ``_clip`` (NaN kept);
* numpy's dot product of two short vectors (``(point - a).dot(ab)``, ``gap.dot(gap)``,
  ``_norm``) summed in coordinate order, as numpy's ``dot`` (OpenBLAS ``ddot``'s scalar
  loop for fewer than 16 elements) sums them (tests compare bit for bit);
* ``bisect_right`` on the arc lengths by a linear scan (the same index).

So the new positions, velocities, the leader's progress and its travel are the
reference's bits (tests: whole runs and single steps, 2-D and 3-D).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tether.silent.steering_kernels import team_steps_kernel


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
    progress_m, advance_m, window_m, dt_s, gamma, d0_m, d_max, r_err, ang, min_sep, max_step,
    search,
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
                               float(cum[-1]), pts[-1], 0.0, 1.0, 30.0, 1.0, 0.2, 8.0, 15.0,
                               0.4, 0.2, 0.5, np.inf, search)  # fmt: skip
