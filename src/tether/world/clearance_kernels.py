"""Compiled kernels of :mod:`tether.world.clearance` (numba; imported only when used).

:func:`build_tree` builds a k-d tree of the obstacle points with tight boxes;
:func:`segments_nearest` finds, per segment, the obstacle point of least clearance by
a depth-first search of that tree ordered and pruned by the exact segment-to-box
distance, after the grid's distance-field bound (when there is one) has settled the
segments far from every obstacle. The distance of a point is computed with exactly the
arithmetic of the reference search (:meth:`ObstacleIndex._segment_clearance_reference`)
and ties go to the lowest point index, as there, so both return the same bits. The
reference's dot products are ``numpy.einsum("kd,kd->k")``, whose summation order for three
terms depends on numpy's SIMD build (``(x0 + x2) + x1`` with two-lane vectors):
:func:`tether.world.clearance.einsum_order` probes it once and the kernel follows.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

LEAF_SIZE = 32
_STACK = 256  # depth-first stack (the tree is balanced: depth ~ log2(m / LEAF_SIZE) + 1)
_PRUNE_REL = 1e-9  # a box is skipped only if its distance exceeds the best by this much


@njit(cache=True, inline="always")
def edot(x, y, order):  # noqa: ANN001, ANN201
    """``sum_d x[d] y[d]`` in the order of ``numpy.einsum`` (``order``: see
    :func:`tether.world.clearance.einsum_order`)."""
    if order == 1 and x.shape[0] == 3:
        return (x[0] * y[0] + x[2] * y[2]) + x[1] * y[1]
    acc = 0.0
    for d in range(x.shape[0]):
        acc += x[d] * y[d]
    return acc


@njit(cache=True)
def build_tree(points, leaf_size):  # noqa: ANN001, ANN201
    """A balanced k-d tree (median splits along the widest side of tight boxes).

    Returns ``spts`` (the points in leaf order), ``perm`` (their indices), and per node
    the box ``lo``, ``hi``, the first child ``child`` (the second is ``child + 1``;
    ``-1`` for a leaf), the range ``start:end`` of ``perm`` it holds, and the box's
    centre ``cen`` and half diagonal ``rad``.
    """
    m, dim = points.shape
    perm = np.arange(m)
    cap = 4 * (m // max(leaf_size, 1) + 1) + 4
    lo = np.empty((cap, dim))
    hi = np.empty((cap, dim))
    child = np.full(cap, -1, np.int64)
    start = np.zeros(cap, np.int64)
    end = np.zeros(cap, np.int64)
    stack = np.empty(cap, np.int64)
    start[0], end[0] = 0, m
    stack[0] = 0
    top, count = 1, 1
    while top > 0:
        top -= 1
        node = stack[top]
        s, e = start[node], end[node]
        for d in range(dim):
            lo[node, d] = np.inf
            hi[node, d] = -np.inf
        for k in range(s, e):
            p = perm[k]
            for d in range(dim):
                x = points[p, d]
                lo[node, d] = min(lo[node, d], x)
                hi[node, d] = max(hi[node, d], x)
        if e - s <= leaf_size:
            continue
        axis, width = 0, -1.0
        for d in range(dim):
            if hi[node, d] - lo[node, d] > width:
                axis, width = d, hi[node, d] - lo[node, d]
        vals = np.empty(e - s)
        for k in range(s, e):
            vals[k - s] = points[perm[k], axis]
        order = np.argsort(vals, kind="mergesort")
        part = perm[s:e][order].copy()
        perm[s:e] = part
        mid = (s + e) // 2
        left = count
        count += 2
        child[node] = left
        start[left], end[left] = s, mid
        start[left + 1], end[left + 1] = mid, e
        stack[top] = left
        stack[top + 1] = left + 1
        top += 2
    lo, hi = lo[:count].copy(), hi[:count].copy()
    cen = 0.5 * (lo + hi)
    rad = np.empty(count)
    for node in range(count):
        r = 0.0
        for d in range(dim):
            r += (0.5 * (hi[node, d] - lo[node, d])) ** 2
        rad[node] = math.sqrt(r) * (1.0 + 1e-12)
    spts = np.empty((m, dim))
    for e in range(m):
        spts[e] = points[perm[e]]
    return spts, perm, lo, hi, child[:count].copy(), start[:count].copy(), end[:count].copy(), \
        cen, rad  # fmt: skip


@njit(cache=True, inline="always")
def point_sq(spts, e, sa, ab, den, order):  # noqa: ANN001, ANN201
    """``(squared distance, parameter)`` from point ``spts[e]`` to the segment ``sa + s ab``.

    The arithmetic of the reference search: the parameter is the einsum-ordered dot
    product of ``spts[e] - sa`` with ``ab`` (:func:`edot`) over ``den``, clipped to
    ``[0, 1]``; the squared distance sums the coordinates in order. (Written without a
    scratch array: a scratch array passed in costs a reference count per call.)
    """
    dim = sa.shape[0]
    t = 0.0
    if order == 1 and dim == 3:
        t = ((spts[e, 0] - sa[0]) * ab[0] + (spts[e, 2] - sa[2]) * ab[2]) \
            + (spts[e, 1] - sa[1]) * ab[1]  # fmt: skip
    else:
        for d in range(dim):
            t += (spts[e, d] - sa[d]) * ab[d]
    s = t / den
    if s < 0.0:
        s = 0.0
    elif s > 1.0:
        s = 1.0
    sq = 0.0
    for d in range(dim):
        x = sa[d] + s * ab[d] - spts[e, d]
        sq += x * x
    return sq, s


@njit(cache=True, inline="always")
def closer(sq, s, p, e, best, best_s, best_i, best_e):  # noqa: ANN001, ANN201, PLR0913
    """The nearest point so far, after one whose squared distance ``sq`` did not rule it
    out (parameter ``s``, index ``p``, position ``e``): ``(d, s, index, position)``, ties to
    the lowest index."""
    dd = math.sqrt(sq)
    if dd < best or (best_i >= 0 and dd == best and p < best_i):
        return dd, s, p, e
    return best, best_s, best_i, best_e


@njit(cache=True, inline="always")
def _node_gaps(sa, sb, ab, den, lo, hi, cen, node):  # noqa: ANN001, ANN202
    """Squared lower-bound ingredients of the distance from a segment to ``node``'s points.

    ``gap2``: squared gap between the node's box and the segment's bounding box;
    ``cen2``: squared distance from the box centre to the segment. The node is farther
    than ``r`` if ``gap2 > r^2`` or ``cen2 > (r + rad)^2`` (``rad``: half diagonal).
    (The exact segment-to-box distance prunes a few more nodes but costs more.)
    """
    dim = sa.shape[0]
    gap2 = 0.0
    num = 0.0
    for d in range(dim):
        top = max(sa[d], sb[d])
        bot = min(sa[d], sb[d])
        if lo[node, d] > top:
            gap2 += (lo[node, d] - top) ** 2
        elif hi[node, d] < bot:
            gap2 += (bot - hi[node, d]) ** 2
        num += (cen[node, d] - sa[d]) * ab[d]
    s = min(max(num / den, 0.0), 1.0)
    cen2 = 0.0
    for d in range(dim):
        x = sa[d] + s * ab[d] - cen[node, d]
        cen2 += x * x
    return gap2, cen2


@njit(cache=True)
def _field_clear(a, b, threshold, field, strides, shape, origin, res, margin):  # noqa: ANN001, ANN202
    """True if the distance field proves the segment's clearance ``>= threshold``.

    Sphere tracing: at a segment point ``x`` the field gives ``||x - o|| >= g =
    DF(c(x)) - margin`` for every obstacle point ``o`` (``margin``: half a cell
    diagonal, twice unless the points are cell centres), so every segment point within
    ``g - threshold`` of ``x`` has clearance ``>= threshold``; the next sample is that
    far along. Gives up (False) outside the grid or when the step falls below a
    quarter cell.
    """
    dim = a.shape[0]
    length = 0.0
    for d in range(dim):
        length += (b[d] - a[d]) ** 2
    length = math.sqrt(length)
    inv = 1.0 / length if length > 0 else 0.0
    t = 0.0  # arc length of the sample
    while True:
        frac = min(t * inv, 1.0)
        flat = 0
        for d in range(dim):
            c = int(math.floor((a[d] + frac * (b[d] - a[d]) - origin[d]) / res))
            if c < 0 or c >= shape[d]:
                return False  # outside the grid the field is 0
            flat += c * strides[d]
        # 1e-9 m for the rounding of the sample's position
        step = field[flat] - margin - threshold - 1e-9
        if step < 0.25 * res:
            return False
        if t + step >= length:
            return True
        t += step


@njit(cache=True)
def field_below_kernel(points, field, strides, shape, origin, res, margin, below):  # noqa: ANN001, ANN201
    """Per point: ``DF(c(x)) - margin < below + 1e-9`` (``DF`` 0 outside the grid).

    The test of :meth:`tether.world.clearance.ObstacleIndex.nearest_min` (its
    ``_field_at``), in the same arithmetic.
    """
    k_pts, dim = points.shape
    out = np.empty(k_pts, np.bool_)
    for k in range(k_pts):
        flat = 0
        inside = True
        for d in range(dim):
            c = int(math.floor((points[k, d] - origin[d]) / res))
            if c < 0 or c >= shape[d]:
                inside = False
                break
            flat += c * strides[d]
        value = field[flat] if inside else 0.0
        out[k] = value - margin < below + 1e-9
    return out


@njit(cache=True)
def _search(spts, perm, lo, hi, child, start, end, cen, rad, sa, sb, ab, den, reach, seed,
            order, stack, stack_g, stack_c):  # noqa: ANN001, ANN202  # fmt: skip
    """Least clearance of one segment below ``reach``: ``(d, s, point)``, point -1 if none.

    ``spts`` are the points in leaf order (``spts[e] = points[perm[e]]``). Depth-first,
    nearer child first, a node skipped when its bound exceeds the best so far (with a
    relative margin for rounding); ``seed`` (a position in ``spts`` or -1) is tried
    first, which only tightens the pruning. A point's distance is computed exactly as
    the reference does, and only for points whose squared distance does not rule them
    out; ties go to the lowest point index.
    """
    best, best_s, best_i, best_e = reach, 0.0, -1, -1
    stack[0] = 0
    stack_g[0] = 0.0
    stack_c[0] = 0.0
    top = 1
    e_seed = seed
    while e_seed >= 0 or top > 0:
        thr = best * (1.0 + _PRUNE_REL) + _PRUNE_REL
        if e_seed >= 0:  # the seed: one point, scanned as a leaf of its own
            e0, e_end = e_seed, e_seed + 1
            e_seed = -1
        else:
            top -= 1
            node = stack[top]
            if stack_g[top] > thr * thr or stack_c[top] > (thr + rad[node]) ** 2:
                continue
            first = child[node]
            if first >= 0:
                g0, c0 = _node_gaps(sa, sb, ab, den, lo, hi, cen, first)
                g1, c1 = _node_gaps(sa, sb, ab, den, lo, hi, cen, first + 1)
                near, far = first, first + 1
                if c1 < c0:
                    near, far, g0, c0, g1, c1 = first + 1, first, g1, c1, g0, c0
                stack[top], stack_g[top], stack_c[top] = far, g1, c1
                stack[top + 1], stack_g[top + 1], stack_c[top + 1] = near, g0, c0
                top += 2
                continue
            e0, e_end = start[node], end[node]
        best2 = best * best * (1.0 + 1e-12)
        for e in range(e0, e_end):
            sq, s = point_sq(spts, e, sa, ab, den, order)
            if sq > best2:
                continue  # sqrt(sq) > best: neither closer nor tied
            best, best_s, best_i, best_e = closer(sq, s, perm[e], e, best, best_s, best_i, best_e)
            best2 = best * best * (1.0 + 1e-12)
    return best, best_s, best_i, best_e


@njit(cache=True)
def segments_nearest(  # noqa: ANN201, PLR0913
    spts, perm, lo, hi, child, start, end, cen, rad, a, b, within,
    field, strides, shape, origin, res, margin, order,
):  # noqa: ANN001  # fmt: skip
    """Per segment ``a[k] -> b[k]``: least clearance below ``within``, its parameter, its point.

    The tree is :func:`build_tree`'s; ``field`` (raveled distance field, empty for
    none), ``strides``, ``shape``, ``origin``, ``res`` and ``margin`` describe the
    grid bound (:func:`_field_clear`); ``order`` is
    :func:`tether.world.clearance.einsum_order`. Returns
    ``dist`` (``inf`` where the clearance is ``>= within``), ``param`` and the index
    of the closest obstacle point (``-1`` where ``dist`` is ``inf``).
    """
    k_seg, dim = a.shape
    dist = np.full(k_seg, np.inf)
    param = np.zeros(k_seg)
    which = np.full(k_seg, -1, np.int64)
    if len(spts) == 0:
        return dist, param, which
    ab = np.empty(dim)
    stack = np.empty(_STACK, np.int64)
    stack_g = np.empty(_STACK)
    stack_c = np.empty(_STACK)
    for k in range(k_seg):
        sa, sb = a[k], b[k]
        if len(field) and _field_clear(sa, sb, within, field, strides, shape, origin, res,
                                       margin):  # fmt: skip
            continue
        for d in range(dim):
            ab[d] = sb[d] - sa[d]
        denom = edot(ab, ab, order)
        den = denom if denom > 0 else 1.0
        d_k, s_k, p_k, _ = _search(
            spts, perm, lo, hi, child, start, end, cen, rad, sa, sb, ab, den, within, -1,
            order, stack, stack_g, stack_c,
        )  # fmt: skip
        if p_k >= 0:
            dist[k], param[k], which[k] = d_k, s_k, p_k
    return dist, param, which
