"""Compiled kernels of App. A: pairs, clearance, weights, Laplacian (numba, lazy).

(The force of a sub-step: :mod:`tether.continuous.connectivity.force_kernels`; the pair
search: :mod:`tether.continuous.connectivity.pair_kernels`.)

:func:`evaluate_fiedler_kernel` is one sub-step's evaluation in one call: the weights,
the eigenpair as :func:`tether.graph.fiedler.fiedler` finds it for ``2 <= n <= 400``
robots from the previous Fiedler vector (up to ``DENSE_MAX_N = 16`` robots the full
``eigh``, LAPACK ``dsyevd`` as numpy's; above, ``method="auto"``: the certified small
solver, ``dsyevr`` when it cannot certify; ``"lapack"``: ``dsyevr``, through
:mod:`tether.graph.lapack_kernels`, the same call as scipy's wrapper) and optionally
the exact force of eq. (17): the same routines in the same order as the Python chain
``compute_weights`` / ``WeightedGraph.fiedler`` / ``gradient.exact_force``, so the
same bits (``tests/test_step_kernels.py``, ``tests/test_fused_substep.py``). A lambda2
at rounding level (``fiedler``'s component check) or a failed ``dsyevr`` is left to
Python (``decided = False``).

The fast paths of :func:`tether.continuous.connectivity.weights.compute_weights`, used when
:func:`tether.jit.enabled`. Each loop does the arithmetic of its numpy reference in the
same order (``np.add.at`` and ``np.bincount`` accumulate in index order; the norm of a
row is ``sqrt((x0^2 + x1^2) + x2^2)``; ``scipy.special.expit(x)`` is
``1 / (1 + exp(-x))``), so both give the same bits; the tests compare them. For a team
of 35 robots the numpy versions are almost all interpreter and dispatch overhead.
"""

from __future__ import annotations

import math
from functools import cache
from typing import TYPE_CHECKING

import numpy as np
from numba import njit

from tether.continuous.connectivity.force_kernels import exact_force_kernel
from tether.continuous.connectivity.pair_kernels import pairs_below, pairs_in_range, row_norm
from tether.continuous.connectivity.potential_kernels import log_derivative1, smooth_step1
from tether.graph import small
from tether.graph.fiedler import _TINY_REL, DENSE_MAX_N
from tether.graph.kernels import laplacian_dense_kernel
from tether.graph.lapack_kernels import syevr_second_kernel
from tether.graph.small import OK
from tether.graph.small_kernels import small_fiedler_kernel
from tether.world.clearance_cache_kernels import segments_nearest_cached

if TYPE_CHECKING:
    from tether.world.clearance import ObstacleIndex


@njit(cache=True)
def weights_kernel(  # noqa: ANN201, PLR0913
    q, pairs, has_obstacles, clearance, s_star, o_star, rs_inner, rs, ro, ro_outer, rc, rc_outer
):  # noqa: ANN001
    """Every array of :class:`tether.continuous.connectivity.weights.WeightedGraph` for ``pairs``.

    ``pairs`` are within ``Rs``; ``clearance``, ``s_star``, ``o_star`` are the
    obstacle search's results for them (ignored unless ``has_obstacles``). Returns
    ``pair_factor, dP_di, dP_dj, clearance, collision, coll_pairs, coll_unit,
    coll_logd``, each computed as :func:`~tether.continuous.connectivity.weights.compute_weights`
    does.
    """
    n, dim = q.shape
    m = len(pairs)
    d_ = np.empty(m)
    u = np.empty((m, dim))
    diff = np.empty(dim)
    a_fac = np.empty(m)
    da = np.empty(m)
    for k in range(m):
        i, j = pairs[k, 0], pairs[k, 1]
        if dim == 3:  # row_norm's sum unrolled, the same order (faster than the loop over dim)
            x0, x1, x2 = q[i, 0] - q[j, 0], q[i, 1] - q[j, 1], q[i, 2] - q[j, 2]
            dk = math.sqrt((x0 * x0 + x1 * x1) + x2 * x2)
            den = max(dk, 1e-300)
            u[k, 0], u[k, 1], u[k, 2] = x0 / den, x1 / den, x2 / den
        else:
            for c in range(dim):
                diff[c] = q[i, c] - q[j, c]
            dk = row_norm(diff)
            den = max(dk, 1e-300)
            for c in range(dim):
                u[k, c] = diff[c] / den
        d_[k] = dk
        a_fac[k], da_k = smooth_step1(rs_inner + rs - dk, rs_inner, rs)  # A = S(R's + Rs - d)
        da[k] = -da_k
    dP_di = np.empty((m, dim))
    dP_dj = np.empty((m, dim))
    b_fac = np.ones(m)
    clear = np.full(m, np.inf)
    if has_obstacles:
        clear = clearance.copy()
        for k in range(m):
            i, j = pairs[k, 0], pairs[k, 1]
            near = np.isfinite(clearance[k])
            b_fac[k], db = smooth_step1(clearance[k] if near else ro_outer, ro, ro_outer)
            s = s_star[k]
            inv = max(clearance[k], 1e-300)
            for c in range(dim):
                p_star = q[i, c] + s * (q[j, c] - q[i, c])
                grad_d = (p_star - o_star[k, c]) / inv if near else 0.0
                dB_di = (db * (1.0 - s)) * grad_d
                dB_dj = (db * s) * grad_d
                dP_di[k, c] = (da[k] * u[k, c]) * b_fac[k] + a_fac[k] * dB_di
                dP_dj[k, c] = (-da[k] * u[k, c]) * b_fac[k] + a_fac[k] * dB_dj
    else:
        for k in range(m):
            for c in range(dim):
                dP_di[k, c] = da[k] * u[k, c]
                dP_dj[k, c] = -dP_di[k, c]
    pair_factor = np.empty(m)
    for k in range(m):
        pair_factor[k] = a_fac[k] * b_fac[k]
    close = d_ < rc_outer
    mc = int(close.sum())
    coll_pairs = np.empty((mc, 2), pairs.dtype)
    coll_unit = np.empty((mc, dim))
    coll_logd = np.empty(mc)
    gamma = np.empty(mc)
    kc = 0
    for k in range(m):
        if close[k]:
            coll_pairs[kc, 0], coll_pairs[kc, 1] = pairs[k, 0], pairs[k, 1]
            coll_unit[kc] = u[k]
            gamma[kc] = smooth_step1(d_[k], rc, rc_outer)[0]
            coll_logd[kc] = log_derivative1(d_[k], rc, rc_outer)
            kc += 1
    # collision_factor: np.add.at over the first column, then over the second
    logc = np.zeros(n)
    zero = np.zeros(n, np.bool_)
    for col in range(2):
        for k in range(mc):
            if gamma[k] > 0:
                logc[coll_pairs[k, col]] += math.log(gamma[k])
    for k in range(mc):
        if not gamma[k] > 0:
            zero[coll_pairs[k, 0]] = True
            zero[coll_pairs[k, 1]] = True
    collision = np.empty(n)
    for r in range(n):
        collision[r] = 0.0 if zero[r] else math.exp(logc[r])
    return pair_factor, dP_di, dP_dj, clear, collision, coll_pairs, coll_unit, coll_logd


@cache
def no_obstacles(dim: int) -> tuple:
    """:func:`evaluate_kernel`'s obstacle arguments for a world without obstacle points.

    Arrays of the types an obstacle index passes, so that both share one compilation
    (made once per dimension: they are read only where there are obstacles).
    """
    i, f1, f2 = np.zeros(0, np.int64), np.zeros(0), np.zeros((0, dim))
    tree = (f2, i, f2, f2, i, i, i, f2, f1)
    table = (np.full(2, -1, np.int64), f1, f2, f2, i, i, i, i, i, f2, np.zeros(2, np.int64))
    return f2, tree, table, 0, (f1, i, i, np.zeros(dim), 1.0, 0.0)


@njit(cache=True)
def evaluate_kernel(  # noqa: ANN201, PLR0913
    q, rs_inner, rs, ro, ro_outer, rc, rc_outer, want_laplacian, obstacles, points, tree,
    table, used, slack, field, order,
):  # noqa: ANN001  # fmt: skip
    """:func:`~tether.continuous.connectivity.weights.compute_weights` in one call, plus
    ``W`` and ``L``.

    Pairs (:func:`pairs_in_range`), their clearance (``obstacles``: the cached search
    :func:`~tether.world.clearance_cache_kernels.segments_nearest_cached` on ``points``,
    ``tree``, ``table`` with ``used`` slots filled, keys ``i n + j``), the weights
    (:func:`weights_kernel`), ``W_ij`` and, with ``want_laplacian``, the dense
    Laplacian (:func:`tether.graph.kernels.laplacian_dense_kernel`). Returns those and
    the number of table slots added, or -1 (and nothing computed) when the table
    would be more than half full: the caller enlarges it and calls again.
    """
    n, dim = q.shape
    pairs = pairs_in_range(q, rs)
    m = len(pairs)
    clear = np.zeros(0)
    s_star = np.zeros(0)
    o_star = np.zeros((0, dim))
    added = 0
    has_obstacles = obstacles and m > 0
    if has_obstacles:
        if used + m > len(table[0]) // 2:
            added = -1
        else:
            a = np.empty((m, dim))
            b = np.empty((m, dim))
            keys = np.empty(m, np.int64)
            for k in range(m):
                a[k] = q[pairs[k, 0]]
                b[k] = q[pairs[k, 1]]
                keys[k] = pairs[k, 0] * n + pairs[k, 1]
            spts, perm, lo, hi, child, start, end, cen, rad = tree
            (
                t_keys,
                t_bound,
                t_a,
                t_b,
                t_seed,
                t_first,
                t_count,
                t_epoch,
                pool,
                pool_x,
                pool_used,
            ) = table
            f_flat, f_strides, f_shape, f_origin, f_res, f_margin = field
            clear, s_star, which, added = segments_nearest_cached(
                spts, perm, lo, hi, child, start, end, cen, rad, a, b, ro_outer, keys, slack,
                t_keys, t_bound, t_a, t_b, t_seed, t_first, t_count, t_epoch, pool, pool_x,
                pool_used,
                f_flat, f_strides, f_shape, f_origin, f_res, f_margin, order,
            )  # fmt: skip
            o_star = np.zeros((m, dim))
            for k in range(m):
                if which[k] >= 0:
                    o_star[k] = points[which[k]]
    if added < 0:
        z = np.zeros((0, dim))
        return (np.zeros(0), z, z, np.zeros(0), np.zeros(0), pairs[:0].copy(), z, np.zeros(0),
                pairs, np.zeros(0), np.zeros((0, 0)), added)  # fmt: skip
    return _graph_arrays(q, pairs, has_obstacles, clear, s_star, o_star, rs_inner, rs, ro,
                         ro_outer, rc, rc_outer, want_laplacian, added)  # fmt: skip


@njit(cache=True)
def _graph_arrays(  # noqa: ANN202, PLR0913
    q, pairs, has_obstacles, clear, s_star, o_star, rs_inner, rs, ro, ro_outer, rc, rc_outer,
    want_laplacian, added,
):  # noqa: ANN001  # fmt: skip
    """:func:`evaluate_kernel`'s tuple from the pairs and their clearance: the weights,
    ``W_ij`` and (``want_laplacian``) the dense Laplacian, then ``added``."""
    pf, dP_di, dP_dj, clear, coll, coll_pairs, coll_unit, coll_logd = weights_kernel(
        q, pairs, has_obstacles, clear, s_star, o_star, rs_inner, rs, ro, ro_outer, rc, rc_outer
    )
    m = len(pairs)
    w = np.empty(m)
    for k in range(m):
        w[k] = pf[k] * coll[pairs[k, 0]] * coll[pairs[k, 1]]
    lap = laplacian_dense_kernel(len(q), pairs, w) if want_laplacian else np.zeros((0, 0))
    return pf, dP_di, dP_dj, clear, coll, coll_pairs, coll_unit, coll_logd, pairs, w, lap, added


@njit(cache=True)
def _maybe_tiny(lam, lap, m):  # noqa: ANN001, ANN202
    """:func:`tether.graph.fiedler._maybe_tiny` with the dense Laplacian."""
    if m == 0:
        return True
    dmax = lap[0, 0]
    for r in range(1, lap.shape[0]):
        dmax = max(dmax, lap[r, r])
    return lam <= _TINY_REL * dmax * (1.0 + 1e-6)


@njit(cache=True)
def fiedler_kernel(lap, m, guess, lapack, small, lwork, liwork):  # noqa: ANN001, ANN201, PLR0913
    """:func:`tether.graph.fiedler.fiedler` of a dense Laplacian with ``m`` links from
    ``guess`` (``2 <= n <= 400``): ``(decided, lambda2, vector, status)``.

    Up to ``DENSE_MAX_N`` nodes the full ``eigh`` (numba's calls LAPACK ``dsyevd`` as
    numpy's does: the same bits). Above, ``lapack``: ``dsyevr`` (``method="lapack"``),
    else the small solver with the settings ``small`` first (``"auto"``; ``status`` is
    its status, -1 if it did not run). ``decided = False``: the caller must run
    ``fiedler`` (lambda2 may be at rounding level, or ``dsyevr`` failed).
    """
    status = -1
    lam = 0.0
    vec = guess
    solved = False
    if lap.shape[0] <= DENSE_MAX_N:
        vals, vecs = np.linalg.eigh(lap)
        lam, vec = max(vals[1], 0.0), vecs[:, 1].copy()
        solved = True
    elif not lapack:
        status, lam, vec, _, _ = small_fiedler_kernel(lap, guess, *small)
        solved = status == OK
    if not solved:
        val, vec, found, info = syevr_second_kernel(lap, lwork, liwork)
        if info != 0 or found != 1:
            return False, 0.0, guess.copy(), status
        lam = max(val, 0.0)
    if _maybe_tiny(lam, lap, m):
        return False, 0.0, guess.copy(), status
    if np.dot(vec, guess) < 0:
        vec = -vec
    return True, lam, vec, status


@njit(cache=True)
def evaluate_fiedler_kernel(  # noqa: ANN201, PLR0913
    q, rs_inner, rs, ro, ro_outer, rc, rc_outer, obstacles, points, tree, table, used, slack,
    field, order, guess, lapack, small, lwork, liwork, potential, with_force,
):  # noqa: ANN001  # fmt: skip
    """:func:`~tether.continuous.connectivity.kernels.evaluate_kernel` (with the Laplacian), then
    :func:`fiedler_kernel` on it from ``guess``, then with ``with_force`` the force of
    the eigenpair (``potential = (lambda2_min, lambda2_null, gain)``).

    Returns ``evaluate_kernel``'s tuple, ``(decided, lambda2, vector, status)`` and the
    force (``(0, dim)`` when not made); ``decided = False`` and nothing after the
    weights when the clearance table must grow (``out[-1] < 0``).
    """
    out = evaluate_kernel(q, rs_inner, rs, ro, ro_outer, rc, rc_outer, True, obstacles, points,
                          tree, table, used, slack, field, order)  # fmt: skip
    return _eigen_and_force(out, guess, lapack, small, lwork, liwork, potential, with_force)


@njit(cache=True)
def evaluate_fiedler_free_kernel(  # noqa: ANN201, PLR0913
    q, rs_inner, rs, ro, ro_outer, rc, rc_outer, guess, lapack, small, lwork, liwork, potential,
    with_force,
):  # noqa: ANN001  # fmt: skip
    """:func:`evaluate_fiedler_kernel` in a world without obstacle points: the same
    result, without the ~30 empty arrays of an obstacle state to pass (for 35 robots
    their conversion was about 3 us of a 50 us call)."""
    pairs = pairs_in_range(q, rs)
    z = np.zeros(0)
    out = _graph_arrays(q, pairs, False, z, z, np.zeros((0, q.shape[1])), rs_inner, rs, ro,
                        ro_outer, rc, rc_outer, True, 0)  # fmt: skip
    return _eigen_and_force(out, guess, lapack, small, lwork, liwork, potential, with_force)


@njit(cache=True)
def _eigen_and_force(out, guess, lapack, small, lwork, liwork, potential, with_force):  # noqa: ANN001, ANN202, PLR0913
    """The rest of :func:`evaluate_fiedler_kernel` after the weights ``out``."""
    n, dim = len(out[4]), out[1].shape[1]  # robots (collision factors), dimension
    none = np.zeros((0, dim))
    if out[-1] < 0:
        return out, (False, 0.0, guess.copy(), -1), none
    pf, dP_di, dP_dj, _, coll, coll_pairs, coll_unit, coll_logd, pairs, _, lap, _ = out
    eigen = fiedler_kernel(lap, len(pairs), guess, lapack, small, lwork, liwork)
    if not (with_force and eigen[0]):
        return out, eigen, none
    force = exact_force_kernel(n, pairs, pf, coll, dP_di, dP_dj, coll_pairs, coll_unit,
                               coll_logd, eigen[2], eigen[1], potential[0], potential[1],
                               potential[2])  # fmt: skip
    return out, eigen, force


def tiny_team() -> tuple[np.ndarray, np.ndarray, ObstacleIndex, tuple, np.ndarray]:
    """The warm-ups' input: three robots in 3-D near one obstacle point.

    Returns ``q``, its pairs within 6 m, the :class:`tether.world.clearance.ObstacleIndex`
    of the obstacle points, :func:`weights_kernel`'s output for the pairs (Table 2's
    outdoor radii) and a Fiedler vector ``nu``.
    """
    from tether.world.clearance import ObstacleIndex

    q = np.array([[0.0, 0.0, 1.0], [2.0, 0.0, 1.0], [1.0, 1.5, 1.0]])
    pairs = pairs_in_range(q, 6.0)
    index = ObstacleIndex(np.array([[1.0, 0.5, 1.0], [5.0, 5.0, 5.0]]), 3)
    i, j = pairs[:, 0], pairs[:, 1]
    clear, s, o = index.segment_clearance_kernel(q[i], q[j], 1.75, i * 3 + j)
    out = weights_kernel(q, pairs, True, clear, s, o, 2.5, 6.0, 0.75, 1.75, 1.0, 2.5)
    return q, pairs, index, out, np.array([-0.5, 0.0, 0.5])


def warm_up() -> None:
    """Compile (or load) every kernel of a sub-step's App. A chain on :func:`tiny_team`.

    The pair search, the obstacle clearance, the weights, the eigenpair and the force,
    each called once with the types the ``connectivity`` strategy passes
    (:mod:`tether.kernel_cache` calls it with every other package's warm-up).
    """
    from tether.continuous.connectivity.force_kernels import warm_up as force_warm_up
    from tether.graph.lapack_kernels import warm_up as lapack_warm_up
    from tether.world.clearance_kernels import field_below_kernel

    q, pairs, index, out, nu = tiny_team()
    pairs_below(q, pairs, 6.0)
    i, j = pairs[:, 0], pairs[:, 1]
    index.segment_clearance_kernel(q[i], q[j], 1.75)
    ones = np.ones(3, dtype=np.int64)
    field_below_kernel(q, np.zeros(1), ones, ones, np.zeros(3), 1.0, 0.5, 1.0)
    force_warm_up(q, pairs, out, nu)
    laplacian_dense_kernel(3, pairs, out[0])
    lapack_warm_up()
    radii, potential = (2.5, 6.0, 0.75, 1.75, 1.0, 2.5), (0.0, 0.5, 1.0)
    for obs in (None, index):
        points_, tree, table, used, fld = no_obstacles(3) if obs is None else \
            obs.kernel_state(3)  # fmt: skip
        has = obs is not None
        evaluate_kernel(q, *radii, True, has, points_, tree, table, used, 0.25, fld, 1)
        for lapack in (False, True):
            evaluate_fiedler_kernel(q, *radii, has, points_, tree, table, used, 0.25, fld, 1, nu,
                                    lapack, small.SETTINGS, 78, 30, potential, True)  # fmt: skip
            if not has:
                evaluate_fiedler_free_kernel(q, *radii, nu, lapack, small.SETTINGS, 78, 30,
                                             potential, True)  # fmt: skip
    small_fiedler_kernel(np.array([[1.0, -1.0], [-1.0, 1.0]]), nu[:2].copy(), *small.SETTINGS)
