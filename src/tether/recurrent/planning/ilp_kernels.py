"""Compiled max-flow and minimal separators for the ILP's cut separation (numba).

The same minimum cuts as :meth:`tether.recurrent.planning.ilp_model.DirectedCutModel._min_cut`
(scipy's ``maximum_flow`` on a sparse matrix rebuilt for every sink), found by
shortest augmenting paths (Edmonds and Karp, "Theoretical improvements in algorithmic
efficiency for network flow problems", J. ACM 19, 1972) on the arc arrays directly.
Capacities are the same integers (``x*`` scaled), so the flow value is exact, and both
cuts returned are unique for every maximum flow: the sink side of the source-nearest
minimum cut (vertices not reachable from ``b`` in the residual graph) and the back cut
(vertices that reach the sink in it). So the cuts (4) separated are identical to the
reference's. Imported only when :func:`tether.jit.enabled`.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def _augment(tail, head, out_ptr, out_arcs, in_ptr, in_arcs, cap, flow, t, via, queue):  # noqa: ANN001, ANN202, PLR0913
    """One shortest augmenting ``0 -> t`` path in the residual graph; its amount (0: none).

    ``via[v]`` is ``a + 1`` when ``v`` was reached forward along arc ``a`` and
    ``-(a + 1)`` when reached backward (undoing flow on ``a``).
    """
    n = len(via)
    for v in range(n):
        via[v] = 0
    via[0] = n + len(tail) + 1  # the source: marked, no arc
    queue[0] = 0
    lo, hi = 0, 1
    while lo < hi and via[t] == 0:
        u = queue[lo]
        lo += 1
        for k in range(out_ptr[u], out_ptr[u + 1]):
            a = out_arcs[k]
            w = head[a]
            if via[w] == 0 and cap[a] > flow[a]:
                via[w] = a + 1
                queue[hi] = w
                hi += 1
        for k in range(in_ptr[u], in_ptr[u + 1]):
            a = in_arcs[k]
            w = tail[a]
            if via[w] == 0 and flow[a] > 0:
                via[w] = -(a + 1)
                queue[hi] = w
                hi += 1
    if via[t] == 0:
        return 0
    amount = np.int64(1) << 62
    v = t
    while v != 0:
        a = via[v]
        if a > 0:
            amount = min(amount, cap[a - 1] - flow[a - 1])
            v = tail[a - 1]
        else:
            amount = min(amount, flow[-a - 1])
            v = head[-a - 1]
    v = t
    while v != 0:
        a = via[v]
        if a > 0:
            flow[a - 1] += amount
            v = tail[a - 1]
        else:
            flow[-a - 1] -= amount
            v = head[-a - 1]
    return amount


@njit(cache=True)
def _residual_reach(
    start, fwd_ptr, fwd_arcs, fwd_end, rev_ptr, rev_arcs, rev_end, cap, flow, queue
):  # noqa: ANN001, ANN202, PLR0913
    """Vertices reached from ``start`` in the residual graph, by breadth-first search.

    From ``u`` it follows the arcs ``fwd_arcs[fwd_ptr[u]:fwd_ptr[u + 1]]`` that have
    capacity left, to ``fwd_end[a]``, and the arcs ``rev_arcs[...]`` that carry flow, to
    ``rev_end[a]``. Out-arcs to heads with in-arcs to tails is the source side's
    search; in-arcs to tails with out-arcs to heads searches backwards from the sink.
    """
    n = len(fwd_ptr) - 1
    seen = np.zeros(n, np.bool_)
    seen[start] = True
    queue[0] = start
    lo, hi = 0, 1
    while lo < hi:
        u = queue[lo]
        lo += 1
        for k in range(fwd_ptr[u], fwd_ptr[u + 1]):
            a = fwd_arcs[k]
            if not seen[fwd_end[a]] and cap[a] > flow[a]:
                seen[fwd_end[a]] = True
                queue[hi] = fwd_end[a]
                hi += 1
        for k in range(rev_ptr[u], rev_ptr[u + 1]):
            a = rev_arcs[k]
            if not seen[rev_end[a]] and flow[a] > 0:
                seen[rev_end[a]] = True
                queue[hi] = rev_end[a]
                hi += 1
    return seen


@njit(cache=True)
def min_cut_kernel(tail, head, out_ptr, out_arcs, in_ptr, in_arcs, cap, t, enough, scale):  # noqa: ANN001, ANN201, PLR0913
    """Maximum flow ``0 -> t`` under integer capacities ``cap`` (arcs ``tail -> head``).

    ``out_arcs[out_ptr[v]:out_ptr[v + 1]]`` are the arcs leaving ``v``, ``in_arcs``
    likewise those entering it. Stops as soon as the flow reaches ``enough``
    (``flow / scale >= enough``: no cut for this sink, masks not computed). Returns
    ``(flow / scale, inside, back)``: ``inside`` marks the vertices the source cannot
    reach in the residual graph, ``back`` those that reach ``t`` in it.
    """
    n = len(out_ptr) - 1
    flow = np.zeros(len(tail), np.int64)
    via = np.zeros(n, np.int64)
    queue = np.empty(n, np.int64)
    total = np.int64(0)
    inside = np.zeros(n, np.bool_)
    back = np.zeros(n, np.bool_)
    while True:
        amount = _augment(tail, head, out_ptr, out_arcs, in_ptr, in_arcs, cap, flow, t, via, queue)
        if amount == 0:
            break
        total += amount
        if total / scale >= enough:
            return total / scale, inside, back
    # source side: reachable from 0 along residual arcs
    inside = ~_residual_reach(0, out_ptr, out_arcs, head, in_ptr, in_arcs, tail, cap, flow, queue)
    # sink side: reaches t along residual arcs (followed backwards: u -> v forward has
    # capacity left on (u, v), w -> v backward has flow on (v, w))
    back = _residual_reach(t, in_ptr, in_arcs, tail, out_ptr, out_arcs, head, cap, flow, queue)
    return total / scale, inside, back


@njit(cache=True)
def minimal_separator_kernel(indptr, indices, sep, t):  # noqa: ANN001, ANN201
    """:meth:`NodeSeparatorModel.minimal`: the vertices of ``sep`` next to both sides.

    ``indptr``/``indices`` are the CSR adjacency; ``sep`` separates vertex 0 from
    ``t``. Keeps those with a neighbour in the component of ``t`` in the graph
    without ``sep``, then of those, those with a neighbour in the component of 0.
    """
    n = len(indptr) - 1
    removed = np.zeros(n, np.bool_)
    for v in sep:
        removed[v] = True
    seen = np.zeros(n, np.bool_)
    near = np.zeros(n, np.bool_)
    queue = np.empty(n, np.int64)
    for start in (t, 0):
        seen[:] = False
        near[:] = False
        seen[start] = True
        queue[0] = start
        lo, hi = 0, 1
        while lo < hi:
            u = queue[lo]
            lo += 1
            for k in range(indptr[u], indptr[u + 1]):
                w = indices[k]
                near[w] = True
                if not seen[w] and not removed[w]:
                    seen[w] = True
                    queue[hi] = w
                    hi += 1
        for v in range(n):
            removed[v] = removed[v] and near[v]
    return np.flatnonzero(removed)


def warm_up() -> None:
    """Compile (or load from numba's cache) the kernel on a three-vertex graph."""
    tail = np.array([0, 1, 0, 2], dtype=np.int64)
    head = np.array([1, 2, 2, 1], dtype=np.int64)
    out_ptr = np.array([0, 2, 3, 4], dtype=np.int64)
    out_arcs = np.array([0, 2, 1, 3], dtype=np.int64)
    in_ptr = np.array([0, 0, 2, 4], dtype=np.int64)
    in_arcs = np.array([0, 3, 1, 2], dtype=np.int64)
    cap = np.array([5, 3, 1, 0], dtype=np.int64)
    min_cut_kernel(tail, head, out_ptr, out_arcs, in_ptr, in_arcs, cap, 2, 1.0, 10.0)
    indptr = np.array([0, 1, 3, 4], dtype=np.int32)  # the path 0 - 1 - 2
    indices = np.array([1, 0, 2, 1], dtype=np.int32)
    minimal_separator_kernel(indptr, indices, np.array([1], dtype=np.int64), 2)
