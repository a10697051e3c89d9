"""Exact Steiner trees on weighted graphs (Dreyfus-Wagner dynamic programme).

The recurrent-connectivity paper (Banfi et al., "Asynchronous multirobot
exploration under recurrent connectivity constraints", Sec. IV-B) calls a
``(delta+1)-Steiner`` routine: an exact Steiner tree for a *small* number of
terminals, polynomial for a fixed number of terminals. This module is that
routine: the Dreyfus-Wagner recursion (1971) over subsets of terminals on top
of all-pairs shortest paths,

    dp[S][v] = cost of a cheapest tree spanning S + {v},
    dp[{t}][v] = d(t, v),
    g[S][u]  = min_{A subset of S, A != 0, S}  dp[A][u] + dp[S \\ A][u],
    dp[S][v] = min_u  d(v, u) + g[S][u],

with ``O(3^k n + 2^k n^2)`` work for ``k`` terminals on ``n`` vertices (every
step is a vectorised numpy min). The shared multi-subset variant used by the
approximation algorithm lives in :mod:`tether.recurrent.planning.apx`; both reuse the
reconstruction helper :func:`reconstruct_tree` below.

:func:`steiner_tree` first shrinks the problem with the exact degree reductions of
:mod:`tether.recurrent.planning.steiner_reduce` (fewer vertices, often fewer
terminals), then runs the same recursion on what is left: compiled
(:mod:`tether.recurrent.planning.steiner_kernels`) when :func:`tether.jit.enabled`,
otherwise :func:`sparse_dreyfus_wagner`, the numpy variant that relaxes over the edge
list instead of an ``n x n`` distance table.
"""

from __future__ import annotations

from collections.abc import Hashable, Iterable, Sequence
from functools import lru_cache
from typing import NamedTuple

import networkx as nx
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import dijkstra

from tether import jit
from tether.recurrent.planning.steiner_reduce import reduce_instance

__all__ = ["MAX_TABLE_BYTES", "SteinerTree", "steiner_tree", "table_bytes"]

MAX_TABLE_BYTES = 2 * 1024**3
"""The largest dynamic-programming tables :func:`steiner_tree` allocates: three
``(2^(k-1), n)`` arrays of 8-byte entries for ``k`` terminals on ``n`` vertices
(2 GiB: 21 terminals on 100 vertices are refused, 20 allowed)."""


def table_bytes(terminals: int, vertices: int) -> int:
    """Bytes of :func:`steiner_tree`'s tables for that many distinct terminals and
    vertices in their component: three ``(2^(terminals-1), vertices)`` arrays."""
    return 3 * 8 * (1 << max(terminals - 1, 0)) * vertices


class SteinerTree(NamedTuple):
    """Result of :func:`steiner_tree`: ``cost, tree = steiner_tree(...)``."""

    cost: float
    """Total weight of the optimal tree (0 for fewer than two terminals)."""
    tree: nx.Graph
    """The tree: a subgraph of the input with its edge data; leaves are terminals."""


def steiner_tree(
    graph: nx.Graph, terminals: Iterable[Hashable], weight: str = "weight"
) -> SteinerTree:
    """Minimum-weight tree of ``graph`` that spans all ``terminals``.

    Parameters
    ----------
    graph
        Undirected ``networkx.Graph``; edge attribute ``weight`` holds the
        non-negative cost (missing attribute: cost 1, as in networkx).
    terminals
        Vertices to connect (duplicates ignored).
    weight
        Name of the edge attribute with the cost.

    Returns
    -------
    SteinerTree
        ``(cost, tree)``. The tree has every terminal, is acyclic and its
        non-terminal vertices all have degree >= 2.

    Raises
    ------
    networkx.NetworkXNoPath
        If the terminals are not all in one connected component.
    ValueError
        For a directed graph, an unknown terminal, a negative weight, or more terminals
        than tables of :data:`MAX_TABLE_BYTES` hold (the message gives the size).

    Notes
    -----
    The degree reductions of :mod:`tether.recurrent.planning.steiner_reduce` run first;
    the programme below runs on the reduced graph. With :func:`tether.jit.enabled`, the
    compiled variant of :mod:`tether.recurrent.planning.steiner_kernels` (Dijkstra
    relaxations, ``O(3^k n + 2^k (m + n) log n)``) finds the optimum; otherwise
    :func:`sparse_dreyfus_wagner` (numpy, ``O(3^k n + 2^k m h)`` for ``h`` rounds) finds
    the same one. Memory is ``O(2^k n)`` for ``k`` terminals, ``n`` vertices and ``m``
    edges left after the reductions: on the SteinLib B instances (50-100 vertices) the
    compiled variant takes milliseconds for up to 13 terminals and seconds for 19 (the
    ``steiner_scaling`` row of ``python benchmarks/run.py``); each terminal more triples
    the work. Optimality is exact (integer or float weights; with float weights the last
    bits of the cost may differ between the two variants, sums being added in another
    order).
    """
    if graph.is_directed():
        raise ValueError("steiner_tree needs an undirected graph")
    terms = list(dict.fromkeys(terminals))
    for t in terms:
        if t not in graph:
            raise ValueError(f"terminal {t!r} is not a vertex of the graph")
    if len(terms) <= 1:
        tree = nx.Graph()
        tree.add_nodes_from((t, graph.nodes[t]) for t in terms)
        return SteinerTree(0.0, tree)
    # Only the component holding the terminals matters.
    nodes = _component(graph, terms[0])
    if len(nodes) < len(graph):
        comp = set(nodes)
        if any(t not in comp for t in terms):
            raise nx.NetworkXNoPath("the terminals are not connected in the graph")
    need = table_bytes(len(terms), len(nodes))
    if need > MAX_TABLE_BYTES:
        raise ValueError(
            f"steiner_tree: {len(terms)} terminals on {len(nodes)} vertices need "
            f"{need / 1024**3:.1f} GiB of tables (MAX_TABLE_BYTES allows "
            f"{MAX_TABLE_BYTES / 1024**3:g} GiB); "
            "use fewer terminals or an approximation "
            "(networkx.algorithms.approximation.steiner_tree)"
        )
    index = {v: i for i, v in enumerate(nodes)}
    us, vs, ws = _edge_lists(graph, nodes, index, weight)
    w = np.array(ws, dtype=float)
    bad = (w < 0) | ~np.isfinite(w)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise ValueError(f"edge ({nodes[us[k]]!r}, {nodes[vs[k]]!r}) has invalid weight {ws[k]}")
    red = reduce_instance(len(nodes), us, vs, w.tolist(), [index[t] for t in terms])
    cost, chosen = red.fixed_cost, list(red.fixed)
    if len(red.terminals) > 1:
        solve = _solve_kernel if jit.enabled() else sparse_dreyfus_wagner
        rest, pairs = solve(red.size, red.us, red.vs, red.ws, red.terminals)
        edge_of = {}
        for i, (a, b) in enumerate(zip(red.us.tolist(), red.vs.tolist(), strict=True)):
            edge_of[a, b] = edge_of[b, a] = i
        cost += rest
        for a, b in pairs:
            chosen.extend(red.paths[edge_of[a, b]])
    edges = [(nodes[us[i]], nodes[vs[i]]) for i in chosen]
    return SteinerTree(float(cost), _as_tree(graph, edges, terms, weight))


def _solve_kernel(
    n: int, us: np.ndarray, vs: np.ndarray, ws: np.ndarray, terminals: list[int]
) -> tuple[float, list[tuple[int, int]]]:
    """Optimal tree of the terminals of a reduced graph (positive weights) by the
    compiled kernels, as :func:`sparse_dreyfus_wagner` finds it: its cost and edges as
    vertex pairs."""
    from tether.recurrent.planning.steiner_kernels import steiner_kernel, tree_edges

    src = np.concatenate([us, vs])
    dst = np.concatenate([vs, us])
    order = np.argsort(src, kind="stable")
    indptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(src, minlength=n), out=indptr[1:])
    term_idx = np.array(terminals, dtype=np.int64)
    weights = np.concatenate([ws, ws])[order]
    cost, pred, split = steiner_kernel(indptr, dst[order], weights, term_idx)
    if not np.isfinite(cost):  # the terminals are connected: only a pruning bug gets here
        raise RuntimeError("steiner_kernel pruned every tree of the terminals")
    edges = tree_edges(pred, split, int(term_idx[-1]), (1 << (len(terminals) - 1)) - 1)
    return float(cost), [(a, b) for a, b in edges.tolist()]


def _component(graph: nx.Graph, start: Hashable) -> list:
    """The vertices of ``start``'s connected component, in breadth-first order (a plain
    search: networkx's ``node_connected_component`` pays for its dispatch on a
    process's first call)."""
    adj = graph.adj
    seen = {start}
    order = [start]
    for v in order:
        for x in adj[v]:
            if x not in seen:
                seen.add(x)
                order.append(x)
    return order


def _edge_lists(
    graph: nx.Graph, nodes: list, index: dict, weight: str
) -> tuple[list[int], list[int], list]:
    """The component's edges as three lists (indices of both ends, weight), each edge once
    and in the order of ``graph.subgraph(nodes).edges(data=weight, default=1.0)``
    (networkx's edge view: nodes in adjacency order, each edge from the end met first),
    self-loops left out. For a whole simple graph the adjacency dicts are read directly
    (``Graph.adjacency``), the same order without the view's generator."""
    us: list[int] = []
    vs: list[int] = []
    ws: list = []
    if len(nodes) < graph.number_of_nodes() or graph.is_multigraph():
        for u, v, w in graph.subgraph(nodes).edges(data=weight, default=1.0):
            if u != v:
                us.append(index[u])
                vs.append(index[v])
                ws.append(w)
        return us, vs, ws
    seen: set = set()
    for u, nbrs in graph.adjacency():
        iu = index[u]
        for v, data in nbrs.items():
            if v not in seen and v != u:
                us.append(iu)
                vs.append(index[v])
                ws.append(data.get(weight, 1.0))
        seen.add(u)
    return us, vs, ws


def all_pairs(
    n: int, rows: Sequence[int], cols: Sequence[int], vals: Sequence[float]
) -> tuple[np.ndarray, np.ndarray]:
    """All-pairs shortest path lengths and predecessors of an undirected graph.

    Edges are given once each as ``(rows[i], cols[i], vals[i])``. scipy drops
    zero-weight entries of sparse input, so zero costs are stored as a tiny
    positive value and the distances rounded back.
    """
    rows_arr, cols_arr = np.asarray(rows, dtype=np.int64), np.asarray(cols, dtype=np.int64)
    vals_arr = np.asarray(vals, dtype=float)
    vals_arr = np.where(vals_arr == 0, 1e-300, vals_arr)  # tiny: scipy drops explicit zeros
    # the CSR arrays directly (scipy's conversion from COO costs more than the search on
    # small graphs); each edge in its first end's row, the search reads both directions
    order = np.argsort(rows_arr, kind="stable")
    indptr = np.zeros(n + 1, dtype=np.int64)
    np.cumsum(np.bincount(rows_arr, minlength=n), out=indptr[1:])
    mat = sp.csr_matrix((vals_arr[order], cols_arr[order], indptr), shape=(n, n))
    dist, pred = dijkstra(mat, directed=False, return_predecessors=True)
    dist[dist < 1e-200] = 0.0
    return dist, pred


def dreyfus_wagner(
    dist: np.ndarray, pred: np.ndarray, terminals: Sequence[int]
) -> tuple[float, list[tuple[int, int]]]:
    """Dreyfus-Wagner on a distance matrix; returns the cost and the tree edges.

    ``terminals`` are vertex indices into ``dist`` (at least two, distinct);
    ``pred`` is the shortest-path predecessor matrix matching ``dist``. The
    last terminal is the root: the optimum is ``dp[T - root][root]``.
    """
    k = len(terminals) - 1
    root = terminals[-1]
    others = list(terminals[:-1])
    n = dist.shape[0]
    full = (1 << k) - 1
    dp = np.empty((1 << k, n))
    dp[0] = 0.0
    via = np.zeros((1 << k, n), dtype=np.intp)  # argmin u of the relaxation
    split = np.zeros((1 << k, n), dtype=np.intp)  # best part A of S at u
    for i, t in enumerate(others):
        dp[1 << i] = dist[t]
        via[1 << i] = t
    for s in range(1, full + 1):
        if s & (s - 1) == 0:
            continue
        low = s & -s
        rest = s ^ low
        # proper subsets A of s that contain the lowest bit: A = low | B, B proper subset of rest
        parts = []
        b = rest
        while True:
            b = (b - 1) & rest
            parts.append(low | b)
            if b == 0:
                break
        parts_arr = np.asarray(parts, dtype=np.intp)
        merged = dp[parts_arr] + dp[s ^ parts_arr]
        best = np.argmin(merged, axis=0)
        g = merged[best, np.arange(n)]
        split[s] = parts_arr[best]
        if s == full:
            total = g + dist[:, root]
            u = int(np.argmin(total))
            cost = float(total[u])
            via[s, root] = u
            break
        relax = g[:, None] + dist  # relax[u, v] = g[u] + d(u, v)
        via[s] = np.argmin(relax, axis=0)
        dp[s] = relax[via[s], np.arange(n)]
    else:  # k == 1: a shortest path
        cost = float(dist[others[0], root])
        via[full, root] = others[0]
    edges = reconstruct_tree(
        pred, root, full, lambda s, v: int(via[s, v]), lambda s, u: int(split[s, u])
    )
    return cost, edges


def sparse_dreyfus_wagner(
    n: int, us: np.ndarray, vs: np.ndarray, ws: np.ndarray, terminals: Sequence[int]
) -> tuple[float, list[tuple[int, int]]]:
    """Dreyfus-Wagner with numpy on the edges, without all-pairs distances.

    The recursion of :func:`dreyfus_wagner` with every subset of one size done at once:
    their merges (``2^(j-1) - 1`` parts per subset of ``j`` terminals, those holding its
    lowest terminal) are one array operation, and their relaxations
    ``dp[S][v] = min_u g[S][u] + d(u, v)`` are Bellman-Ford rounds over the edge list
    for all of them together (each round a segment minimum over the arcs into every
    vertex) until nothing improves: ``O(3^k n + 2^k m h)`` for ``h`` rounds (the most
    edges on a shortest path), and no ``n x n`` table. Weights must be positive (the
    reductions contract zero-weight edges), so the predecessors found afterwards, an arc
    whose sum gives the label exactly, never form a cycle. Returns the cost and the tree
    edges as vertex pairs.
    """
    k = len(terminals) - 1
    full = (1 << k) - 1
    src = np.concatenate([us, vs])
    dst = np.concatenate([vs, us])
    order = np.argsort(dst, kind="stable")
    src, dst, w = src[order], dst[order], np.concatenate([ws, ws])[order]
    starts = np.flatnonzero(np.r_[True, dst[1:] != dst[:-1]])  # every vertex has an arc
    dp = np.full((1 << k, n), np.inf)
    pred = np.full((1 << k, n), -1, dtype=np.intp)
    split = np.zeros((1 << k, n), dtype=np.intp)
    for j in range(1, k + 1):
        subsets, parts = _level(k, j)
        if j == 1:
            labels = np.full((k, n), np.inf)
            labels[np.arange(k), terminals[:-1]] = 0.0
        else:
            merged = dp[parts] + dp[subsets[:, None] ^ parts]  # (subsets, parts, n)
            best = np.argmin(merged, axis=1)
            labels = np.take_along_axis(merged, best[:, None, :], axis=1)[:, 0, :]
            split[subsets] = np.take_along_axis(parts, best, axis=1)
        start = labels.copy()
        while True:
            reach = np.minimum.reduceat(labels[:, src] + w, starts, axis=1)
            better = reach < labels
            if not better.any():
                break
            labels = np.where(better, reach, labels)
        dp[subsets] = labels
        sums = labels[:, src] + w
        rows, arcs = np.nonzero((sums == labels[:, dst]) & (labels[:, dst] < start[:, dst]))
        pred[subsets[rows], dst[arcs]] = src[arcs]
    root = terminals[-1]
    edges: list[tuple[int, int]] = []
    stack = [(full, root)]
    while stack:
        s, v = stack.pop()
        while pred[s, v] >= 0:
            edges.append((int(pred[s, v]), v))
            v = int(pred[s, v])
        if s & (s - 1):
            a = int(split[s, v])
            stack.append((a, v))
            stack.append((s ^ a, v))
    return float(dp[full, root]), edges


@lru_cache(maxsize=64)
def _level(k: int, j: int) -> tuple[np.ndarray, np.ndarray]:
    """The subsets of ``j`` of ``k`` terminals (bit masks) and, per subset, its parts
    holding its lowest bit (``(subsets, 2^(j-1) - 1)``)."""
    subsets = [s for s in range(1 << k) if s.bit_count() == j]
    parts = []
    for s in subsets:
        low = s & -s
        rest = s ^ low
        row, b = [], rest
        while True:
            b = (b - 1) & rest
            row.append(low | b)
            if b == 0:
                break
        parts.append(row)
    return np.array(subsets, dtype=np.intp), np.array(parts, dtype=np.intp)


def reconstruct_tree(pred, root, full, via_of, split_of) -> list[tuple[int, int]]:
    """Edges of the Dreyfus-Wagner tree for subset ``full`` hanging from ``root``.

    ``via_of(S, v)`` gives the vertex ``u`` where the tree of ``S + {v}`` branches
    (for a singleton ``S = {t}``, ``u = t``) and ``split_of(S, u)`` a part ``A`` of
    ``S`` with which the branch splits at ``u``. Shortest paths come from the
    predecessor matrix ``pred``. Returns undirected edges (possibly repeated).
    """
    edges: list[tuple[int, int]] = []
    stack = [(full, root)]
    while stack:
        s, v = stack.pop()
        u = via_of(s, v)
        edges.extend(_path_edges(pred, v, u))
        if s & (s - 1):
            a = split_of(s, u)
            stack.append((a, u))
            stack.append((s ^ a, u))
    return edges


def _path_edges(pred: np.ndarray, src: int, dst: int) -> list[tuple[int, int]]:
    out = []
    cur = dst
    while cur != src:
        p = int(pred[src, cur])
        if p < 0:
            raise nx.NetworkXNoPath(f"no path between vertex indices {src} and {dst}")
        out.append((p, cur))
        cur = p
    return out


def _as_tree(
    graph: nx.Graph, edges: list[tuple[Hashable, Hashable]], terminals: list, weight: str
) -> nx.Graph:
    """Turn a union of shortest paths (and fixed edges, some of them in a part without
    terminals when weights are zero) into a tree: MST of the union, then prune leaves."""
    sub = nx.Graph()
    sub.add_nodes_from((t, graph.nodes[t]) for t in terminals)
    for a, b in edges:
        sub.add_edge(a, b, **graph.edges[a, b])
        sub.nodes[a].update(graph.nodes[a])
        sub.nodes[b].update(graph.nodes[b])
    tree = _spanning_tree(sub, weight)
    term = set(terminals)
    leaves = [v for v in tree if tree.degree(v) <= 1 and v not in term]
    while leaves:
        v = leaves.pop()
        if v not in tree:  # listed twice: both ends of a lone edge
            continue
        nbrs = list(tree.neighbors(v))
        tree.remove_node(v)
        leaves.extend(u for u in nbrs if tree.degree(u) <= 1 and u not in term)
    return tree


def _spanning_tree(sub: nx.Graph, weight: str) -> nx.Graph:
    """``networkx.minimum_spanning_tree(sub, weight=weight)`` (Kruskal), the same graph.

    The union of shortest paths is usually a tree already; then Kruskal keeps every edge,
    in the order it sorts them (by weight, stable), and that graph is made directly,
    without the union-find and networkx's dispatch.
    """
    n = sub.number_of_nodes()
    if sub.number_of_edges() != n - 1 or (n and len(_component(sub, next(iter(sub)))) != n):
        return nx.minimum_spanning_tree(sub, weight=weight)
    tree = nx.Graph()
    tree.graph.update(sub.graph)
    tree.add_nodes_from(sub.nodes.items())
    tree.add_edges_from(sorted(sub.edges(data=True), key=lambda e: e[2].get(weight, 1)))
    return tree
