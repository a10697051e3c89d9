"""Compiled exact Steiner tree: Dreyfus-Wagner with Dijkstra relaxations (numba).

The same dynamic programme as :func:`tether.recurrent.planning.steiner.dreyfus_wagner`
(Dreyfus and Wagner, "The Steiner problem in graphs", Networks 1, 1971), with its
relaxation step ``dp[S][v] = min_u g[S][u] + d(u, v)`` done by one Dijkstra run from
every vertex at once, started at the labels ``g[S]``, instead of through an all-pairs
distance matrix: the variant of Erickson, Monma and Veinott ("Send-and-split method
for minimum-concave-cost network flows", Math. Oper. Res. 12, 1987). Time
``O(3^k n + 2^k (m + n) log n)`` for ``k + 1`` terminals, ``n`` vertices and ``m``
edges (the reference: ``O(3^k n + 2^k n^2)`` plus all-pairs shortest paths), memory
``O(2^k n)``.

Labels that cannot be part of a tree cheaper than the best one known are pruned, so
most of the ``2^k`` Dijkstra runs touch few vertices, and a merge of two subsets whose
cheapest labels (with the bound below) already exceed it is skipped whole. The best tree
known starts as a 2-approximation (the terminals' distance-graph MST) and improves as
soon as a subset and its complement are both done (their two trees at a vertex plus the
path from there to the root span every terminal). The lower bound on the rest of a tree
at ``v`` is the larger of the farthest terminal outside the subset and half a 1-tree of
``v`` and those terminals, the bounds of Hougardy, Silvanus and Vygen ("Dijkstra meets
Steiner", Math. Prog. Comp. 9, 2017, Sec. 4). The optimum is the same as the
reference's; with non-integer weights its last bits may differ (sums are added in
another order). Imported only when :func:`tether.jit.enabled`.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _push(keys, verts, size, key, vert):  # noqa: ANN001, ANN202
    """Insert into the binary min-heap ``keys``/``verts`` holding ``size`` items."""
    i = size
    keys[i] = key
    verts[i] = vert
    while i > 0:
        parent = (i - 1) >> 1
        if keys[parent] <= keys[i]:
            break
        keys[i], keys[parent] = keys[parent], keys[i]
        verts[i], verts[parent] = verts[parent], verts[i]
        i = parent
    return size + 1


@njit(cache=True)
def _pop(keys, verts, size):  # noqa: ANN001, ANN202
    """Remove the minimum of the heap; returns it and the new size."""
    key, vert = keys[0], verts[0]
    size -= 1
    keys[0] = keys[size]
    verts[0] = verts[size]
    _sift_down(keys, verts, size, 0)
    return key, vert, size


@njit(cache=True)
def _sift_down(keys, verts, size, i):  # noqa: ANN001, ANN202
    """Move item ``i`` of the heap down to its place."""
    while True:
        left = 2 * i + 1
        if left >= size:
            break
        child = left
        if left + 1 < size and keys[left + 1] < keys[left]:
            child = left + 1
        if keys[i] <= keys[child]:
            break
        keys[i], keys[child] = keys[child], keys[i]
        verts[i], verts[child] = verts[child], verts[i]
        i = child


@njit(cache=True)
def relax(indptr, indices, weights, dist, pred, keys, verts, lb, limit):  # noqa: ANN001, ANN201, PLR0913
    """Dijkstra from every vertex with a finite label in ``dist`` (updated in place).

    ``pred[v]`` becomes the previous vertex on the cheapest path (-1 for a vertex
    whose own label was not improved: the path's source). A label ``d`` at ``v``
    with ``d + lb[v] > limit`` is not kept (pruning, see :func:`steiner_kernel`).
    ``keys``/``verts`` are work arrays of length at least ``n + len(indices)``.
    """
    n = len(dist)
    size = 0
    done = np.zeros(n, np.bool_)
    for v in range(n):  # the finite labels, then heapified bottom-up in O(n)
        if dist[v] < np.inf:
            keys[size] = dist[v]
            verts[size] = v
            size += 1
    for i in range(size // 2 - 1, -1, -1):
        _sift_down(keys, verts, size, i)
    while size > 0:
        d, u, size = _pop(keys, verts, size)
        if done[u] or d > dist[u]:
            continue
        done[u] = True
        for e in range(indptr[u], indptr[u + 1]):
            v = indices[e]
            nd = d + weights[e]
            if nd < dist[v] and nd + lb[v] <= limit:
                dist[v] = nd
                pred[v] = u
                size = _push(keys, verts, size, nd, v)


@njit(cache=True)
def steiner_kernel(indptr, indices, weights, terminals):  # noqa: ANN001, ANN201
    """Dreyfus-Wagner over subsets of ``terminals[:-1]``, rooted at ``terminals[-1]``.

    The graph is symmetric CSR (each undirected edge in both rows). Returns the cost
    of the optimal tree, ``pred`` (per subset, the Dijkstra predecessors) and
    ``split`` (per subset and vertex, the part ``A`` of ``S`` the tree branches
    with): :func:`tree_edges` turns them into the tree's edges.
    """
    k = len(terminals) - 1
    n = len(indptr) - 1
    full = (1 << k) - 1
    root = terminals[k]
    dp = np.full((full + 1, n), np.inf)
    pred = np.full((full + 1, n), -1, np.int64)
    split = np.zeros((full + 1, n), np.int64)
    keys = np.empty(n + len(indices))
    verts = np.empty(n + len(indices), np.int64)
    zero = np.zeros(n)
    # distances from every terminal (the singletons' rows, and the root's)
    dterm = np.full((k + 1, n), np.inf)
    scratch = np.full(n, -1, np.int64)
    for i in range(k + 1):
        dterm[i, terminals[i]] = 0.0
        relax(indptr, indices, weights, dterm[i], pred[1 << i] if i < k else scratch, keys,
              verts, zero, np.inf)  # fmt: skip
        if i < k:
            dp[1 << i] = dterm[i]
    limit = _with_slack(_upper_bound(dterm, terminals))
    lb = np.empty(n)
    work = np.empty((2, n))
    lowest = np.zeros(full + 1)  # per subset, its cheapest label (0 for a singleton)
    for s in range(1, full + 1):
        if s & (s - 1) == 0:
            continue
        lower_bounds(dterm, terminals, s, lb, work)
        lb_min = lb.min()
        low = s & -s
        rest = s ^ low
        row = dp[s]
        b = rest
        while True:  # parts A = low | B, B a proper subset of rest, as the reference
            b = (b - 1) & rest
            a = low | b
            c = s ^ a
            # every v of the pair fails the test below when its cheapest sum does (floating
            # point addition is monotone), so skipping the pair changes nothing
            if lowest[a] + lowest[c] + lb_min <= limit:
                pa, pc = dp[a], dp[c]
                for v in range(n):
                    val = pa[v] + pc[v]
                    if val < row[v] and val + lb[v] <= limit:
                        row[v] = val
                        split[s, v] = a
            if b == 0:
                break
        relax(indptr, indices, weights, row, pred[s], keys, verts, lb, limit)
        lowest[s] = row.min()
        c = full ^ s
        if c and (c < s or c & (c - 1) == 0):  # both halves done: the trees of S + {v}
            # and of T - S + {v} with the path v -> root span every terminal
            best = np.inf
            pc, to_root = dp[c], dterm[k]
            for v in range(n):
                best = min(best, row[v] + pc[v] + to_root[v])
            limit = min(limit, _with_slack(best))
    return dp[full, root], pred, split


@njit(cache=True)
def _with_slack(cost):  # noqa: ANN001, ANN202
    """The pruning limit for a tree of ``cost``: rounding slack, never prune the optimum."""
    return cost + 1e-9 * max(1.0, cost)


@njit(cache=True)
def lower_bounds(dterm, terminals, s, lb, work):  # noqa: ANN001, ANN201
    """``lb[v]``: a lower bound on the part of a tree outside the labels of subset ``s``.

    A tree of ``S + {v}`` is completed by a tree joining ``v`` to ``R``, the terminals
    outside ``S`` (with the root, ``terminals[-1]``). That costs at least the largest
    distance from ``v`` into ``R``, and at least half a 1-tree (the MST of ``R`` in the
    distance graph plus the two shortest distances from ``v`` into ``R``): a tree,
    walked around, is a tour through ``v`` and ``R``, and a tour costs at least a
    1-tree. ``dterm[i]`` are the distances from ``terminals[i]``; ``work`` is ``(2, n)``
    scratch.
    """
    k = len(terminals) - 1
    members = np.empty(k + 1, np.int64)
    m = 0
    for i in range(k):
        if not (s >> i) & 1:
            members[m] = i
            m += 1
    members[m] = k
    m += 1
    near, second = work[0], work[1]
    lb[:] = dterm[k]
    near[:] = dterm[k]
    second[:] = np.inf
    for j in range(m - 1):
        row = dterm[members[j]]
        for v in range(len(lb)):
            d = row[v]
            lb[v] = max(lb[v], d)
            if d < near[v]:
                second[v] = near[v]
                near[v] = d
            else:
                second[v] = min(second[v], d)
    if m >= 2:
        half = 0.5 * _mst_weight(dterm, terminals, members[:m])
        for v in range(len(lb)):
            lb[v] = max(lb[v], half + 0.5 * (near[v] + second[v]))


@njit(cache=True)
def _upper_bound(dterm, terminals):  # noqa: ANN001, ANN202
    """Weight of a minimum spanning tree of the terminals' distance graph.

    The union of its shortest paths is a connected subgraph holding every terminal,
    so the optimal Steiner tree costs at most this (Kou, Markowsky and Berman 1981).
    """
    return _mst_weight(dterm, terminals, np.arange(len(terminals)))


@njit(cache=True)
def _mst_weight(dterm, terminals, members):  # noqa: ANN001, ANN202
    """Prim's MST weight of the distance graph on ``terminals[members]``.

    ``dterm[i, v]`` is the distance from ``terminals[i]`` to vertex ``v``.
    """
    t = len(members)
    inside = np.zeros(t, np.bool_)
    best = np.full(t, np.inf)
    best[0] = 0.0
    total = 0.0
    for _ in range(t):
        j = -1
        for c in range(t):
            if not inside[c] and (j < 0 or best[c] < best[j]):
                j = c
        inside[j] = True
        total += best[j]
        for c in range(t):
            if not inside[c]:
                best[c] = min(best[c], dterm[members[j], terminals[members[c]]])
    return total


@njit(cache=True)
def tree_edges(pred, split, root, full):  # noqa: ANN001, ANN201
    """Edges ``(m, 2)`` of the tree of :func:`steiner_kernel` (possibly repeated)."""
    out = np.empty((2 * pred.shape[1] * 4 + 16, 2), np.int64)
    count = 0
    stack_s = np.empty(2 * (full + 1) + 2, np.int64)
    stack_v = np.empty(2 * (full + 1) + 2, np.int64)
    top = 1
    stack_s[0], stack_v[0] = full, root
    while top > 0:
        top -= 1
        s, v = stack_s[top], stack_v[top]
        cur = v
        while pred[s, cur] >= 0:
            if count == len(out):
                bigger = np.empty((2 * len(out), 2), np.int64)
                bigger[:count] = out[:count]
                out = bigger
            out[count, 0], out[count, 1] = pred[s, cur], cur
            count += 1
            cur = pred[s, cur]
        if s & (s - 1):
            a = split[s, cur]
            stack_s[top], stack_v[top] = a, cur
            stack_s[top + 1], stack_v[top + 1] = s ^ a, cur
            top += 2
    return out[:count]


def warm_up() -> None:
    """Compile (or load from numba's cache) both kernels on a 3-vertex path."""
    indptr = np.array([0, 1, 3, 4], np.int64)
    indices = np.array([1, 0, 2, 1], np.int64)
    weights = np.array([1.0, 1.0, 2.0, 2.0])
    cost, pred, split = steiner_kernel(indptr, indices, weights, np.array([0, 2], np.int64))
    tree_edges(pred, split, 2, 1)
