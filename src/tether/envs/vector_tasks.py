"""The tasks and observations of :mod:`tether.envs.tasks` / :mod:`.observe` for one copy, compiled.

``task`` is the tuple :func:`tether.envs.vector.task_arrays` makes: the kind
(0 none, 1 leader path, 2 goals, 3 targets), per-copy state arrays (changed in place)
and the scenario's path, goals or target queues, shared by all copies. Each function
computes what its Python counterpart computes, operation for operation where the
floating point matters (the leader's progress, summed in coordinate order like
:mod:`tether.floats`); ``tests/test_envs_vector.py`` compares them.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tether.envs.vector_world import point_free

#: term indices (the order of tether.envs.options.TERMS)
_PROGRESS, _TARGETS = 0, 1
OBS_LIMIT = 1e5


@njit(cache=True, inline="always")
def _dist(x, y):  # noqa: ANN001, ANN202
    """``||x - y||``, summed in coordinate order (no array for the difference)."""
    s = 0.0
    for c in range(len(x)):
        d = x[c] - y[c]
        s += d * d
    return math.sqrt(s)


@njit(cache=True)
def path_at(s, wp, seg, cum, seg_len, length, out):  # noqa: ANN001, ANN201
    """``Polyline.at``: the point at arc length ``s`` into ``out``."""
    s = min(max(s, 0.0), length)
    if wp.shape[0] == 1 or length == 0.0:
        out[:] = wp[0]
        return
    k = np.searchsorted(cum, s, side="right") - 1
    k = min(max(k, 0), len(seg_len) - 1)
    frac = (s - cum[k]) / max(seg_len[k], 1e-12)
    for c in range(wp.shape[1]):
        out[c] = wp[k, c] + frac * seg[k, c]


@njit(cache=True)
def path_project(point, s_min, window, wp, seg, denom, cum, seg_len, length, at):  # noqa: ANN001, ANN201, PLR0913
    """``Polyline.project``: the closest path point's arc length in ``[s_min, s_min + window]``
    (``at``: scratch of ``dim`` values)."""
    best_s, best_d = s_min, np.inf
    dim = wp.shape[1]
    for k in range(len(denom)):
        s0, s1 = cum[k], cum[k + 1]
        if s1 < s_min or s0 > s_min + window:
            continue
        t = 0.0
        if denom[k] != 0:
            acc = 0.0
            for c in range(dim):
                acc += (point[c] - wp[k, c]) * seg[k, c]
            t = min(max(acc / denom[k], 0.0), 1.0)
        s = min(max(s0 + t * (s1 - s0), s_min), s_min + window)
        path_at(s, wp, seg, cum, seg_len, length, at)
        d = _dist(at, point)
        if d < best_d:
            best_s, best_d = s, d
    return best_s


@njit(cache=True)
def task_copy(e, q_old, q, t_s, task, terms, at):  # noqa: ANN001, ANN201, PLR0913
    """Progress of copy ``e``'s move ending at ``t_s`` into ``terms``; True when done
    (``at``: scratch of ``dim`` values)."""
    kind = task[0]
    if kind == 1:
        leader, progress = task[1][e], task[2]
        wp, seg, denom, cum, seg_len, length, end = task[3:10]
        window, tol = task[11], task[12]
        before = progress[e]
        s = path_project(q[leader], before, window, wp, seg, denom, cum, seg_len, length, at)
        progress[e] = max(before, s)
        terms[_PROGRESS] = progress[e] - before
        return _dist(q[leader], end) <= tol
    if kind == 2:
        robots, goals, last = task[14], task[15], task[16]
        gain = 0.0
        for g in range(len(robots)):
            now = _dist(goals[g], q[robots[g]])
            gain += last[e, g] - now
            last[e, g] = now
        terms[_PROGRESS] = gain
        return False
    if kind == 3:
        tq, stay, appear, count, nxt, stayed, completed = task[17:24]
        rz, dt, total = task[24], task[25], task[26]
        gain, done_now = 0.0, 0
        for r in range(tq.shape[0]):
            k = nxt[e, r]
            if k >= count[r] or appear[r, k] > t_s - dt + 1e-12:
                continue
            near = _dist(tq[r, k], q[r])
            gain += _dist(tq[r, k], q_old[r]) - near
            stayed[e, r] = stayed[e, r] + dt if near <= rz else 0.0
            if stayed[e, r] >= stay[r, k] - 1e-9:
                nxt[e, r] += 1
                stayed[e, r] = 0.0
                done_now += 1
        completed[e] += done_now
        terms[_PROGRESS] = gain
        terms[_TARGETS] = done_now
        return completed[e] >= total
    return False


@njit(cache=True)
def _task_vectors(e, q, t_s, task, vec, flag):  # noqa: ANN001, ANN201
    kind = task[0]
    if kind == 1:
        leader = task[1][e]
        wp, seg, denom, cum, seg_len, length = task[3:9]
        path_at(task[2][e] + task[10], wp, seg, cum, seg_len, length, vec[leader])
        vec[leader] -= q[leader]
        flag[leader] = 1.0
    elif kind == 2:
        robots, goals = task[14], task[15]
        for g in range(len(robots)):
            for c in range(q.shape[1]):
                vec[robots[g], c] = goals[g, c] - q[robots[g], c]
            flag[robots[g]] = 1.0
    elif kind == 3:
        tq, appear, count, nxt = task[17], task[19], task[20], task[21]
        for r in range(tq.shape[0]):
            k = nxt[e, r]
            if k < count[r] and appear[r, k] <= t_s + 1e-12:
                for c in range(q.shape[1]):
                    vec[r, c] = tq[r, k, c] - q[r, c]
                flag[r] = 1.0


@njit(cache=True)
def observe_copy(e, q, v, pairs, t_s, sizes, world, task, out, vec, flag, row, nbr, dist, point):  # noqa: ANN001, ANN201, PLR0913
    """Every robot's observation of copy ``e`` into ``out`` (``(n, size)`` float32).

    ``vec`` (``(n, dim)``), ``flag``, ``nbr``, ``dist`` (``n``), ``row`` (``size``) and
    ``point`` (``dim``) are scratch (:func:`tether.envs.vector_kernels.work_arrays`).
    """
    has_grid, free, shape, origin, _, _, has_bounds, bounds, cell_m = world
    n, dim = q.shape
    vmax, range_m = sizes[2], sizes[3]
    k_slots, cells, res = int(sizes[6]), int(sizes[7]), sizes[8]
    centre = task[13][e]
    vec[:] = 0.0
    flag[:] = 0.0
    _task_vectors(e, q, t_s, task, vec, flag)
    width = dim + 2
    for i in range(n):
        row[:] = 0.0
        for c in range(dim):
            row[c] = v[i, c] / vmax
            row[dim + c] = (q[i, c] - centre[c]) / range_m
            row[2 * dim + c] = vec[i, c] / range_m
        row[3 * dim] = flag[i]
        m = 0
        for p in range(len(pairs)):  # neighbours in index order, then sorted (stable)
            j = pairs[p, 1] if pairs[p, 0] == i else (pairs[p, 0] if pairs[p, 1] == i else -1)
            if j < 0:
                continue
            d = _dist(q[j], q[i])
            f = m
            while f > 0 and (dist[f - 1] > d or (dist[f - 1] == d and nbr[f - 1] > j)):
                nbr[f], dist[f] = nbr[f - 1], dist[f - 1]
                f -= 1
            nbr[f], dist[f] = j, d
            m += 1
        base = 3 * dim + 1
        for s in range(min(m, k_slots)):
            for c in range(dim):
                row[base + s * width + c] = (q[nbr[s], c] - q[i, c]) / range_m
            row[base + s * width + dim] = 1.0 - dist[s] / range_m
            row[base + s * width + dim + 1] = 1.0
        if cells > 0 and (has_grid or has_bounds):
            side = 2 * cells + 1
            at = base + k_slots * width
            for idx in range(side**dim):
                rest = idx
                for c in range(dim - 1, -1, -1):
                    point[c] = q[i, c] + (rest % side - cells) * res
                    rest //= side
                blocked = not point_free(
                    point, has_grid, free, shape, origin, cell_m, has_bounds, bounds
                )
                row[at + idx] = 1.0 if blocked else 0.0
        for c in range(len(row)):
            out[i, c] = min(max(row[c], -OBS_LIMIT), OBS_LIMIT)
