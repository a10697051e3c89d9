"""Compiled Dijkstra on a coarse grid (numba; imported only by :mod:`tether.paths.geodesic`).

:func:`grid_dijkstra_kernel` runs Dijkstra's algorithm from each source on the
8-connected graph of :class:`~tether.paths.geodesic.CoarseGrid`, read from the grid
once per call into a table of each node's neighbours (:func:`neighbour_table`). The
graph has two edge weights, so the queue is two FIFO queues, one per weight, instead
of a heap: labels leave the queue in non-decreasing order, so each label pushed onto
a queue (the one just taken plus that queue's weight) is no smaller than the one
pushed before it, each queue stays sorted, and the smaller of the two heads is the
smallest label queued. A label is final when it leaves the queue; an entry whose node
got a smaller label since is skipped.

Distances equal ``scipy.sparse.csgraph.dijkstra``'s bit for bit, whatever order
either queue settles equal labels in: both compute ``d(x) = min_u fl(d(u) + w(u, x))``
with the same additions, whose solution is the smallest left-to-right floating-point
sum over all paths (rounded addition is monotone and never lowers a label, so the
textbook proof of Dijkstra's algorithm holds for those sums).

Predecessors are scipy's where they do not depend on its heap: scipy keeps, for node
``x``, the *first scanned* neighbour ``u`` with ``fl(d(u) + w(u, x)) == d(x)`` (a later
one replaces it only if strictly better). Neighbours with a smaller label are scanned
first by any queue, so that is the candidate with the smallest ``d(u)``; only when two
candidates share it does the order of scipy's Fibonacci heap decide. Those nodes are
flagged in ``tie`` (a small fraction of the nodes of a map; ``tests/test_geodesic_kernel.py``
checks the paths against scipy's) and
:meth:`tether.paths.geodesic.Geodesics.path` asks scipy for the row of a source whose
path crosses one.
"""

from __future__ import annotations

import numpy as np
from numba import njit

NO_PRED = -9999  # scipy's predecessor of a source or an unreached node


@njit(cache=True)
def _offsets(width):  # noqa: ANN001, ANN202
    """Neighbour offsets on the raveled padded grid: 4 orthogonal, then 4 diagonal.

    For a diagonal step ``(sx, sy)``, ``via_x`` and ``via_y`` are the offsets of the
    two orthogonal cells ``(sx, 0)`` and ``(0, sy)`` that must be traversable too.
    """
    step = np.array([-width, width, -1, 1, -width - 1, -width + 1, width - 1, width + 1])
    via_x = np.array([0, 0, 0, 0, -width, -width, width, width])
    via_y = np.array([0, 0, 0, 0, -1, 1, -1, 1])
    return step, via_x, via_y


@njit(cache=True)
def neighbour_table(free, nodes):  # noqa: ANN001, ANN201
    """``(n, 8)`` node ids of each node's neighbours (``-1``: none), as :func:`_offsets`.

    Columns 0-3 are the orthogonal neighbours, 4-7 the diagonal ones, a diagonal one
    only when both orthogonal cells between are traversable (no corner cut).
    """
    width = free.shape[1]
    flat = free.ravel()
    n = len(nodes)
    node_of = np.full(free.size, -1, np.int32)
    for i in range(n):
        node_of[nodes[i]] = i
    step, via_x, via_y = _offsets(width)
    table = np.full((n, 8), -1, np.int32)
    for i in range(n):
        u = nodes[i]
        for j in range(8):
            if not flat[u + step[j]]:
                continue
            if j >= 4 and not (flat[u + via_x[j]] and flat[u + via_y[j]]):
                continue
            table[i, j] = node_of[u + step[j]]
    return table


@njit(cache=True)
def _search(table, w_orth, w_diag, source, d, qa, la, qb, lb):  # noqa: ANN001, ANN202
    """Dijkstra from node ``source`` into ``d`` (``(n,)``, overwritten) with two FIFO queues.

    ``qa``/``la`` hold the nodes and labels pushed along orthogonal edges, ``qb``/``lb``
    along diagonal ones (each at least ``4 n + 1`` long: a node is taken once and
    pushes at most four entries onto each).
    """
    d[:] = np.inf
    d[source] = 0.0
    qa[0] = source
    la[0] = 0.0
    ha, ta, hb, tb = 0, 1, 0, 0
    while True:
        if ha < ta and (hb >= tb or la[ha] <= lb[hb]):
            u, du = qa[ha], la[ha]
            ha += 1
        elif hb < tb:
            u, du = qb[hb], lb[hb]
            hb += 1
        else:
            return
        if du != d[u]:
            continue  # its label fell since (that entry came first)
        nd = du + w_orth
        for j in range(4):
            v = table[u, j]
            if v >= 0 and nd < d[v]:  # never for a taken v: its label is <= du
                d[v] = nd
                qa[ta] = v
                la[ta] = nd
                ta += 1
        nd = du + w_diag
        for j in range(4, 8):
            v = table[u, j]
            if v >= 0 and nd < d[v]:
                d[v] = nd
                qb[tb] = v
                lb[tb] = nd
                tb += 1


@njit(cache=True)
def grid_dijkstra_kernel(free, nodes, w_orth, w_diag, sources, with_pred):  # noqa: ANN001, ANN201
    """Distances, predecessors and ties ``(k, n)`` from each source node.

    ``free``: the traversable mask with a border of blocked cells (``(cx + 2, cy + 2)``);
    ``nodes``: the raveled (C-order) index in it of each node's cell; ``sources``: node
    ids. Orthogonal neighbours cost ``w_orth``, diagonal ones ``w_diag`` when both
    orthogonal cells between are traversable (no corner cut). Unreached nodes get
    ``inf`` and :data:`NO_PRED`, as the source. Without ``with_pred`` the last two
    arrays are empty.
    """
    width = free.shape[1]
    flat = free.ravel()
    n = len(nodes)
    k = len(sources)
    dist = np.empty((k, n))
    rows = k if with_pred else 0
    pred = np.full((rows, n), NO_PRED, np.int32)
    tie = np.zeros((rows, n), np.bool_)
    table = neighbour_table(free, nodes)
    cap = 4 * n + 1
    qa = np.empty(cap, np.int32)
    qb = np.empty(cap, np.int32)
    la = np.empty(cap)
    lb = np.empty(cap)
    if with_pred:
        node_of = np.full(free.size, NO_PRED, np.int32)
        for i in range(n):
            node_of[nodes[i]] = i
        step, via_x, via_y = _offsets(width)
        cost = np.empty(8)
        cost[:4] = w_orth
        cost[4:] = w_diag
        padded = np.full(free.size, np.inf)
    for row in range(k):
        _search(table, w_orth, w_diag, sources[row], dist[row], qa, la, qb, lb)
        if with_pred:
            for i in range(n):
                padded[nodes[i]] = dist[row, i]
            _predecessors(
                flat, padded, nodes, node_of, step, via_x, via_y, cost, pred[row], tie[row]
            )
    return dist, pred, tie


@njit(cache=True)
def _pred_of(flat, d, x, step, via_x, via_y, cost):  # noqa: ANN001, ANN202
    """scipy's predecessor cell of the reached cell ``x`` (not a source), and its tie flag.

    The neighbour ``u`` with ``d(u) < d(x)`` and ``d(u) + w(u, x) == d(x)`` of smallest
    ``d(u)``; ``tie`` when two such neighbours share that label (see the module docstring).
    """
    dx = d[x]
    best = -1
    best_d = np.inf
    tie = False
    for j in range(8):
        u = x + step[j]
        if not flat[u]:
            continue
        if j >= 4 and not (flat[x + via_x[j]] and flat[x + via_y[j]]):
            continue
        du = d[u]
        if du < dx and du + cost[j] == dx:
            if du < best_d:
                best = u
                best_d = du
                tie = False
            elif du == best_d:
                tie = True
    return best, tie


@njit(cache=True)
def _predecessors(flat, d, nodes, node_of, step, via_x, via_y, cost, p, t):  # noqa: ANN001, ANN202
    """scipy's predecessor of every reached node but the source, and its ``tie`` flag."""
    for i in range(len(nodes)):
        x = nodes[i]
        dx = d[x]
        if dx == 0.0 or dx == np.inf:  # the source (edges are positive) or unreached
            continue
        best, tie = _pred_of(flat, d, x, step, via_x, via_y, cost)
        t[i] = tie
        p[i] = node_of[best]


@njit(cache=True)
def trace_kernel(free, nodes, w_orth, w_diag, dist_row, target):  # noqa: ANN001, ANN201
    """Nodes from the source of ``dist_row`` to node ``target`` and whether one is a tie.

    The path that :func:`grid_dijkstra_kernel`'s predecessors (``with_pred``) give,
    computed from the distances of one source alone (``dist_row``, ``(n,)``, as that
    kernel returns them) for the nodes of this one path: the same
    :func:`_pred_of` rule, node by node from ``target`` back to the source.
    ``free`` and ``nodes`` as for :func:`grid_dijkstra_kernel`.
    """
    width = free.shape[1]
    flat = free.ravel()
    d = np.full(free.size, np.inf)
    node_of = np.full(free.size, NO_PRED, np.int32)
    for i in range(len(nodes)):
        d[nodes[i]] = dist_row[i]
        node_of[nodes[i]] = i
    step, via_x, via_y = _offsets(width)
    cost = np.empty(8)
    cost[:4] = w_orth
    cost[4:] = w_diag
    out = [np.int64(target)]
    any_tie = False
    x = nodes[target]
    while d[x] != 0.0 and d[x] != np.inf:
        best, tie = _pred_of(flat, d, x, step, via_x, via_y, cost)
        any_tie = any_tie or tie
        out.append(np.int64(node_of[best]))
        x = best
    path = np.empty(len(out), np.intp)
    for i in range(len(out)):
        path[i] = out[len(out) - 1 - i]
    return path, any_tie


def warm_up() -> None:
    """Compile (or load from numba's cache) the kernel on a 3 x 3 grid."""
    free = np.zeros((5, 5), dtype=bool)
    free[1:4, 1:4] = True
    nodes = np.flatnonzero(free.ravel())
    w_diag = 3.0 * np.sqrt(2.0)
    for with_pred in (False, True):
        dist = grid_dijkstra_kernel(free, nodes, 3.0, w_diag, np.array([4]), with_pred)[0]
    trace_kernel(free, nodes, 3.0, w_diag, dist[0], 0)
