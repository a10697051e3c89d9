"""The cached clearance search of a team's links: bounds and candidate lists per segment key.

A team's links move little between two evaluations of the connectivity force, so
:func:`segments_nearest_cached` keeps, per segment key (``i n + j``), what it learnt the
last time it searched that segment ``a0 -> b0`` and reuses it while the endpoints stay
close (``move``: the larger endpoint displacement since then). Clearance is 1-Lipschitz
in ``move``, which gives two rules, both exact:

* a **bound**: ``bound(a0, b0) - move`` bounds the new clearance from below; at or above
  ``within`` the segment is settled without a search;
* a **candidate list** (segments nearer than ``within``, the ones whose closest point the
  weights need at every evaluation): with ``d0`` the clearance of ``a0 -> b0``, the list
  holds every obstacle point within ``d0 + 2 slack`` of it. While ``move <= slack`` the
  new clearance is at most ``d0 + move`` (the old closest point), and every point that
  close to the new segment lies within ``d0 + 2 move`` of the old one, so it is in the
  list: scanning the list finds what the tree search finds.

A scanned point's distance is computed with exactly the arithmetic of the tree search
(:func:`tether.world.clearance_kernels._search`) and ties go to the lowest point index
there and here, so the result is the same bits whichever way it was found
(``tests/test_clearance_lists.py``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tether.world.clearance_kernels import (
    _PRUNE_REL,
    _STACK,
    _field_clear,
    _node_gaps,
    _search,
    closer,
    edot,
    point_sq,
)

#: relative and absolute widening of a candidate list's radius (rounding of the distances)
_LIST_REL = 1e-9


@njit(cache=True, inline="always")
def _slot(table_keys, key):  # noqa: ANN001, ANN202
    """Slot of ``key`` in an open-addressing table (linear probing): its own or the empty one.

    A key below the table size starts at its own slot (a small team's pair codes ``i n +
    j`` then sit in order, next to each other); others by Fibonacci hashing (the table
    size is a power of 2).
    """
    mask = len(table_keys) - 1
    h = key if 0 <= key <= mask else (key * 0x9E3779B97F4A7C15) & mask
    while table_keys[h] != -1 and table_keys[h] != key:
        h = (h + 1) & mask
    return h


@njit(cache=True)
def _collect(spts, lo, hi, child, start, end, cen, rad, sa, sb, ab, den, radius, order, stack,
             pool, pool_x, first):  # noqa: ANN001, ANN202  # fmt: skip
    """Write into ``pool[first:]`` the positions (in ``spts``) of every point within
    ``radius`` of the segment, and into ``pool_x[first:]`` its coordinates (a list is
    then scanned as one block of memory); return how many, or -1 if the pool is too short.

    The tree's boxes are pruned by the bounds of :func:`~tether.world.clearance_kernels._node_gaps`
    with the same relative margin as the search, so no point within ``radius`` is missed.
    """
    thr = radius * (1.0 + _PRUNE_REL) + _PRUNE_REL
    thr2 = thr * thr
    count = 0
    stack[0] = 0
    top = 1
    while top > 0:
        top -= 1
        node = stack[top]
        gap2, cen2 = _node_gaps(sa, sb, ab, den, lo, hi, cen, node)
        if gap2 > thr2 or cen2 > (thr + rad[node]) ** 2:
            continue
        if child[node] >= 0:
            stack[top] = child[node]
            stack[top + 1] = child[node] + 1
            top += 2
            continue
        for e in range(start[node], end[node]):
            sq, _ = point_sq(spts, e, sa, ab, den, order)
            if sq <= thr2:
                if first + count >= len(pool):
                    return -1
                pool[first + count] = e
                pool_x[first + count] = spts[e]
                count += 1
    return count


@njit(cache=True)
def _scan(perm, pool, pool_x, first, count, sa, ab, den, reach, order):  # noqa: ANN001, ANN202
    """``_search``'s answer over the listed points only: ``(d, s, point, position)``."""
    best, best_s, best_i, best_e = reach, 0.0, -1, -1
    best2 = best * best * (1.0 + 1e-12)
    for k in range(first, first + count):
        sq, s = point_sq(pool_x, k, sa, ab, den, order)  # pool_x[k] is spts[pool[k]]
        if sq > best2:
            continue  # sqrt(sq) > best: neither closer nor tied
        e = pool[k]
        best, best_s, best_i, best_e = closer(sq, s, perm[e], e, best, best_s, best_i, best_e)
        best2 = best * best * (1.0 + 1e-12)
    return best, best_s, best_i, best_e


@njit(cache=True)
def segments_nearest_cached(  # noqa: ANN201, PLR0913
    spts, perm, lo, hi, child, start, end, cen, rad, a, b, within, keys, slack,
    table_keys, table_bound, table_a, table_b, table_seed, table_first, table_count,
    table_epoch, pool, pool_x, pool_used, field, strides, shape, origin, res, margin, order,
):  # noqa: ANN001  # fmt: skip
    """:func:`~tether.world.clearance_kernels.segments_nearest` with a cache per segment key
    (same results).

    The table (open addressing, keys ``-1`` = empty, at most half full) holds, per
    key, the segment ``table_a -> table_b`` last searched, a lower bound of its
    clearance, the closest point found (``table_seed``, its position in ``spts``, -1 if
    none) and, for a segment nearer than ``within``, its candidate list
    (``pool[table_first:table_first + table_count]``, the points' coordinates in the same
    rows of ``pool_x``; ``table_count = -1``: none; a list is valid while its
    ``table_epoch`` is the pool's, ``pool_used[1]``; ``pool_used[0]`` slots are taken; a
    full pool starts again from its first slot in a new epoch, in O(1); an
    empty pool: no lists). A segment whose ``bound - move`` is
    at or above ``within`` is settled; one with a list and ``move <= slack`` is scanned
    over its list; any other is checked against ``within + slack`` (field, then the
    tree search from the old closest point), its entry renewed and, if nearer than
    ``within``, given a new list. Sound whatever the keys. Returns ``dist``, ``param``,
    ``which`` and the number of keys added to the table.
    """
    k_seg, dim = a.shape
    dist = np.full(k_seg, np.inf)
    param = np.zeros(k_seg)
    which = np.full(k_seg, -1, np.int64)
    added = 0
    if len(spts) == 0:
        return dist, param, which, added
    ab = np.empty(dim)
    stack = np.empty(_STACK, np.int64)
    stack_g = np.empty(_STACK)
    stack_c = np.empty(_STACK)
    reach = within + slack
    for k in range(k_seg):
        sa, sb = a[k], b[k]
        for d in range(dim):
            ab[d] = sb[d] - sa[d]
        denom = edot(ab, ab, order)
        den = denom if denom > 0 else 1.0
        h = _slot(table_keys, keys[k])
        seed = -1
        if table_keys[h] == keys[k]:
            move_a, move_b = 0.0, 0.0
            for d in range(dim):
                move_a += (sa[d] - table_a[h, d]) ** 2
                move_b += (sb[d] - table_b[h, d]) ** 2
            move = math.sqrt(max(move_a, move_b))
            if table_bound[h] - move >= within:
                continue  # settled: the entry keeps its old segment and bound
            listed = table_count[h] >= 0 and table_epoch[h] == pool_used[1]
            if listed and move <= slack:  # the list still holds the answer
                d_k, s_k, p_k, e_k = _scan(perm, pool, pool_x, table_first[h],
                                           table_count[h], sa, ab, den, reach, order)  # fmt: skip
                if p_k >= 0:
                    table_seed[h] = e_k  # only ever a seed for the pruning
                    if d_k < within:
                        dist[k], param[k], which[k] = d_k, s_k, p_k
                continue
            seed = table_seed[h]
        else:
            table_keys[h] = keys[k]
            added += 1
        table_a[h] = sa
        table_b[h] = sb
        table_count[h] = -1
        if len(field) and _field_clear(sa, sb, reach, field, strides, shape, origin, res,
                                       margin):  # fmt: skip
            table_bound[h] = reach
            table_seed[h] = -1
            continue
        d_k, s_k, p_k, e_k = _search(
            spts, perm, lo, hi, child, start, end, cen, rad, sa, sb, ab, den, reach, seed,
            order, stack, stack_g, stack_c,
        )  # fmt: skip
        table_bound[h] = d_k if p_k >= 0 else reach
        table_seed[h] = e_k
        if p_k >= 0 and d_k < within:
            dist[k], param[k], which[k] = d_k, s_k, p_k
            if len(pool) == 0:
                continue  # no pool: no lists
            radius = (d_k + 2.0 * slack) * (1.0 + _LIST_REL) + _LIST_REL
            got = _collect(spts, lo, hi, child, start, end, cen, rad, sa, sb, ab, den, radius,
                           order, stack, pool, pool_x, pool_used[0])  # fmt: skip
            if got < 0:  # the pool is full: start it again (lists are only a shortcut)
                pool_used[0] = 0  # every list made before is void: a new epoch
                pool_used[1] += 1
                got = _collect(spts, lo, hi, child, start, end, cen, rad, sa, sb, ab, den,
                               radius, order, stack, pool, pool_x, 0)  # fmt: skip
            if got >= 0:
                table_first[h] = pool_used[0]
                table_count[h] = got
                table_epoch[h] = pool_used[1]
                pool_used[0] += got
    return dist, param, which, added
