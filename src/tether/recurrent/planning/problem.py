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

from collections.abc import Hashable, Iterable, Mapping
from dataclasses import dataclass

import networkx as nx
import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components, shortest_path

UNREACHABLE = np.iinfo(np.int32).max // 4


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
) -> Problem:
    """Transform and reduce an instance (see the module docstring).

    The transformation of Sec. IV-A: every vertex of ``fixed`` is removed;
    those linked to ``b`` through ``fixed`` vertices (relays) give each of
    their other neighbours a fictitious edge to ``b``. A fixed vertex cut off
    from ``b`` relays nothing, so it is removed without adding edges. When
    ``fixed + {b}`` is connected (the paper's readiness rule keeps the relays
    of unfinished frontiers in place) this is exactly the paper's
    transformation.
    """
    validate(graph, base, utilities, budget)
    fixed = frozenset(fixed) - {base}
    for v in fixed:
        if v not in graph:
            raise ValueError(f"non-ready goal {v!r} is not a vertex of the graph")
    budget = int(budget)
    nodes = list(graph)
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
    dist_f, pred = shortest_path(adj, unweighted=True, directed=False, return_predecessors=True)
    dist = np.where(np.isfinite(dist_f), dist_f, UNREACHABLE).astype(np.int32)
    return Problem(labels, adj, dist, pred, util_all[ball], budget, fixed)


def tree_utility(problem: Problem, indices: Iterable[int]) -> float:
    return float(sum(problem.utility[i] for i in set(indices)))
