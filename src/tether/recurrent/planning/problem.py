"""The optimal-configuration instance after the paper's graph transformation.

Shared by the exact (:mod:`._ilp`) and approximate (:mod:`._apx`) solvers.
Implements Sec. IV-A of Banfi et al.: the vertices assigned to non-ready robots
are removed and their neighbours get fictitious communication edges to the
base station ``b``. Then two exact reductions are applied:

* a vertex ``u`` can be in an optimal tree only if ``d(b, u) + d(u, f) <= B``
  for some frontier ``f`` with ``d(b, f) <= B`` (hop distances, ``B`` the
  budget): every vertex of a tree whose leaves are frontiers lies on a
  root-frontier path of at most ``B`` edges;
* frontiers farther than ``B`` hops from ``b`` are dropped.

Vertices are re-indexed ``0..n-1`` with the base at index 0.
"""

from __future__ import annotations

import itertools
from collections.abc import Hashable, Iterable, Mapping
from dataclasses import dataclass

import networkx as nx
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components, shortest_path

UNREACHABLE = np.iinfo(np.int32).max // 4
DENSE_MAX_VERTICES = 3000  # build(method="auto") uses a dense n x n matrix up to this size


@dataclass
class Problem:
    """A reduced instance: unit-cost graph, root 0, frontier utilities, budget."""

    labels: list[Hashable]
    """Original vertex of each index (``labels[0]`` is the base)."""
    adj: sp.csr_matrix
    """Symmetric 0/1 adjacency of the transformed, reduced graph."""
    dist: np.ndarray
    """Hop distances (int32, ``UNREACHABLE`` if none)."""
    pred: np.ndarray
    """Shortest-path predecessors matching ``dist``."""
    utility: np.ndarray
    """``U(v)`` (0 for non-frontiers and for the root)."""
    budget: int
    fixed: frozenset
    """Vertices of non-ready robots that were contracted into the base."""

    @property
    def n(self) -> int:
        return len(self.labels)

    @property
    def frontiers(self) -> np.ndarray:
        """Indices of the frontiers (utility > 0), by decreasing utility."""
        idx = np.flatnonzero(self.utility > 0)
        return idx[np.argsort(-self.utility[idx], kind="stable")]

    def to_labels(self, indices: Iterable[int]) -> frozenset:
        return frozenset(self.labels[i] for i in indices if i != 0)


def validate(
    graph: nx.Graph, base: Hashable, utilities: Mapping[Hashable, float], budget: int
) -> None:
    """Raise ``ValueError`` for inputs outside the model of the paper."""
    if graph.is_directed() or graph.is_multigraph():
        raise ValueError("G^t must be a simple undirected networkx.Graph")
    if base not in graph:
        raise ValueError(f"base vertex {base!r} is not in the graph")
    if int(budget) != budget or budget < 0:
        raise ValueError(f"budget must be a non-negative integer (got {budget!r})")
    for v, u in utilities.items():
        if v not in graph:
            raise ValueError(f"frontier {v!r} is not a vertex of the graph")
        if not np.isfinite(u) or u < 0:
            raise ValueError(f"utility of {v!r} must be finite and >= 0 (got {u!r})")


def adjacency(graph: nx.Graph, index: Mapping[Hashable, int]) -> sp.csr_matrix:
    """Symmetric 0/1 ``int8`` adjacency (no self-loops) in the order of ``index``."""
    n = len(index)
    count = 2 * graph.number_of_edges()
    ends = np.fromiter((index[v] for e in graph.edges() for v in e), dtype=np.intp, count=count)
    ends = ends.reshape(-1, 2)
    ends = ends[ends[:, 0] != ends[:, 1]]
    rows = np.concatenate([ends[:, 0], ends[:, 1]])
    cols = np.concatenate([ends[:, 1], ends[:, 0]])
    adj = sp.csr_matrix((np.ones(len(rows), dtype=np.int8), (rows, cols)), shape=(n, n))
    adj.sum_duplicates()
    adj.data[:] = 1
    return adj


def build(
    graph: nx.Graph,
    base: Hashable,
    utilities: Mapping[Hashable, float],
    budget: int,
    fixed: Iterable[Hashable] = (),
    *,
    method: str = "auto",
) -> Problem:
    """Transform and reduce an instance (see the module docstring).

    The transformation of Sec. IV-A: every vertex of ``fixed`` is removed;
    those linked to ``b`` through ``fixed`` vertices (relays) give each of
    their other neighbours a fictitious edge to ``b``. A fixed vertex cut off
    from ``b`` relays nothing, so it is removed without adding edges. When
    ``fixed + {b}`` is connected (the paper's readiness rule keeps the relays
    of unfinished frontiers in place) this is exactly the paper's
    transformation.

    ``method``: ``"sparse"`` (the reference: scipy sparse matrices and searches),
    ``"dense"`` (the same steps on a boolean matrix, :func:`build_dense`: the same
    problem, without sparse fancy indexing) or ``"auto"`` (dense up to
    :data:`DENSE_MAX_VERTICES` vertices).
    """
    validate(graph, base, utilities, budget)
    fixed = frozenset(fixed) - {base}
    for v in fixed:
        if v not in graph:
            raise ValueError(f"non-ready goal {v!r} is not a vertex of the graph")
    budget = int(budget)
    nodes = list(graph)
    if method == "auto":
        method = "dense" if len(nodes) <= DENSE_MAX_VERTICES else "sparse"
    if method == "dense":
        return build_dense(graph, nodes, base, utilities, budget, fixed)
    if method != "sparse":
        raise ValueError(f"unknown method {method!r}; expected 'auto', 'dense' or 'sparse'")
    index = {v: i for i, v in enumerate(nodes)}
    adj = adjacency(graph, index)
    b = index[base]
    keep = np.ones(len(nodes), dtype=bool)
    if fixed:
        # Sec. IV-A: relays (fixed vertices linked to b through fixed vertices) become b.
        fixed_idx = np.array([index[v] for v in fixed], dtype=np.intp)
        group = np.concatenate([[b], fixed_idx])
        _, lab = connected_components(adj[group][:, group], directed=False)
        relay = group[lab == lab[0]]
        keep[fixed_idx] = False
        extra = np.asarray(adj[relay].sum(axis=0)).ravel() > 0
        extra &= keep
        extra[b] = False
        adj = adj.tolil()
        adj[b, np.flatnonzero(extra)] = 1
        adj[np.flatnonzero(extra), b] = 1
        adj = adj.tocsr()
    sel = np.flatnonzero(keep)
    sel = np.concatenate([[b], sel[sel != b]])  # base first
    adj = adj[sel][:, sel]
    depth = shortest_path(adj, unweighted=True, directed=False, indices=0)
    util_all = np.array([float(utilities.get(nodes[i], 0.0)) for i in sel])
    util_all[0] = 0.0
    ball = np.flatnonzero(depth <= budget)  # includes 0
    is_frontier = (util_all[ball] > 0) & (ball != 0)
    if is_frontier.any():
        sub = adj[ball][:, ball]
        to_f = shortest_path(
            sub, unweighted=True, directed=False, indices=np.flatnonzero(is_frontier)
        ).min(axis=0)
        ball = ball[depth[ball] + to_f <= budget]
    else:
        ball = ball[:1]
    adj = adj[ball][:, ball].astype(float)
    labels = [nodes[i] for i in sel[ball]]
    return finish(labels, adj, util_all[ball], budget, fixed)


def finish(
    labels: list,
    adj: sp.csr_matrix,
    utility: np.ndarray,
    budget: int,
    fixed: frozenset,
    directed: bool = False,
) -> Problem:
    """The :class:`Problem` of the reduced graph ``adj``: all-pairs hop distances.

    scipy's search, whose distances and predecessors the solvers use. ``adj`` is
    symmetric, so ``directed=True`` gives the same matrices as the reference's
    ``directed=False`` (which scans every edge a second time, from the transpose,
    where no label can improve any more; Floyd-Warshall symmetrises an already
    symmetric matrix) in less time (test: ``tests/test_problem_dense.py``).
    """
    dist_f, pred = shortest_path(adj, unweighted=True, directed=directed, return_predecessors=True)
    dist = np.where(np.isfinite(dist_f), dist_f, UNREACHABLE).astype(np.int32)
    return Problem(labels, adj, dist, pred, utility, budget, fixed)


def _levels(adj: np.ndarray, sources: np.ndarray, limit: int) -> np.ndarray:
    """Hop distance from the nearest of ``sources`` (``limit + 1`` beyond ``limit``).

    Breadth-first search by rows of the boolean matrix ``adj``: exact hop counts,
    as scipy's unweighted searches give them (up to ``limit``).
    """
    n = adj.shape[0]
    depth = np.full(n, limit + 1, dtype=np.int64)
    seen = np.zeros(n, dtype=bool)
    seen[sources] = True
    depth[sources] = 0
    layer = np.asarray(sources, dtype=np.intp)
    for level in range(1, limit + 1):
        if not len(layer):
            break
        new = adj[layer].any(axis=0) & ~seen
        layer = np.flatnonzero(new)
        seen[layer] = True
        depth[layer] = level
    return depth


def build_dense(
    graph: nx.Graph,
    nodes: list,
    base: Hashable,
    utilities: Mapping[Hashable, float],
    budget: int,
    fixed: frozenset,
) -> Problem:
    """:func:`build`'s steps on a dense boolean adjacency (inputs validated by it).

    The same relays (the component of ``b`` among ``fixed + {b}``), fictitious edges,
    order (base first), ball of radius ``budget`` and root-frontier reduction, with
    hop counts from breadth-first searches; the reduced graph goes to :func:`finish`
    as a CSR matrix equal to the reference's (sorted indices, data 1.0).
    """
    n = len(nodes)
    index = {v: i for i, v in enumerate(nodes)}
    if nodes == list(range(n)):  # exploration graphs: labels are the indices
        flat = np.fromiter(itertools.chain.from_iterable(graph.edges()), dtype=np.intp)
    else:
        flat = np.fromiter((index[v] for e in graph.edges() for v in e), dtype=np.intp)
    ends = flat.reshape(-1, 2)
    a = np.zeros((n, n), dtype=bool)
    a[ends[:, 0], ends[:, 1]] = True
    a[ends[:, 1], ends[:, 0]] = True
    np.fill_diagonal(a, False)
    b = index[base]
    keep = np.ones(n, dtype=bool)
    if fixed:
        fixed_idx = np.array([index[v] for v in fixed], dtype=np.intp)
        group = np.concatenate([[b], fixed_idx])
        reach = _levels(a[np.ix_(group, group)], np.zeros(1, np.intp), len(group))
        relay = group[reach <= len(group)]
        keep[fixed_idx] = False
        extra = a[relay].any(axis=0) & keep
        extra[b] = False
        a[b, extra] = True
        a[extra, b] = True
    sel = np.flatnonzero(keep)
    sel = np.concatenate([[b], sel[sel != b]])  # base first
    a = a[np.ix_(sel, sel)]
    depth = _levels(a, np.zeros(1, np.intp), budget)
    util_all = np.array([float(utilities.get(nodes[i], 0.0)) for i in sel])
    util_all[0] = 0.0
    ball = np.flatnonzero(depth <= budget)  # includes 0
    is_frontier = (util_all[ball] > 0) & (ball != 0)
    if is_frontier.any():
        to_f = _levels(a[np.ix_(ball, ball)], np.flatnonzero(is_frontier), budget)
        ball = ball[depth[ball] + to_f <= budget]
    else:
        ball = ball[:1]
    adj = sp.csr_matrix(a[np.ix_(ball, ball)].astype(float))
    labels = [nodes[i] for i in sel[ball]]
    return finish(labels, adj, util_all[ball], budget, fixed, directed=True)


def tree_utility(problem: Problem, indices: Iterable[int]) -> float:
    return float(sum(problem.utility[i] for i in set(indices)))
