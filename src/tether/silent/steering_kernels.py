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
