"""Structure of a graph: neighbour pairs, adjacency, Laplacians, components, stretch.

A graph on ``n`` nodes is an ``(m, 2)`` integer array of undirected links
``pairs`` (``i < j``) with optional ``(m,)`` non-negative weights.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components, dijkstra
from scipy.spatial import cKDTree

from tether import jit

#: up to this many robots, :func:`pairs_within` tests all pairs in a compiled kernel
#: once numba is loaded (:func:`tether.jit.warm`); a k-d tree's set-up costs more there
KERNEL_PAIRS_MAX_N = 200


def pairs_within(positions: np.ndarray, range_m: float) -> np.ndarray:
    """All pairs ``(i, j)``, ``i < j``, with ``||p_i - p_j|| <= range_m``.

    Uses a k-d tree, so the cost is ``O(n log n + m)`` rather than all-pairs; small
    teams are tested pair by pair when compiled kernels are loaded
    (:func:`tether.graph.kernels.pairs_within_kernel`, the same squared-distance test),
    larger ones through a cell grid (:mod:`tether.graph.grid_kernels`, the same test).
    """
    positions = np.asarray(positions, dtype=float)
    if len(positions) < 2:
        return np.empty((0, 2), dtype=np.intp)
    if jit.warm() and len(positions) <= KERNEL_PAIRS_MAX_N:
        from tether.graph.kernels import pairs_within_kernel

        return pairs_within_kernel(np.ascontiguousarray(positions), float(range_m))
    if jit.warm() and len(positions) > KERNEL_PAIRS_MAX_N and positions.shape[1] in (2, 3):
        from tether.graph.grid_kernels import grid_shape, pairs_within_grid_kernel

        ncell = grid_shape(positions, float(range_m))
        if ncell is not None:
            return pairs_within_grid_kernel(np.ascontiguousarray(positions), float(range_m), ncell)
    tree = cKDTree(positions)
    pairs = tree.query_pairs(r=float(range_m), output_type="ndarray")
    if len(pairs) == 0:
        return np.empty((0, 2), dtype=np.intp)
    pairs = np.sort(pairs.astype(np.intp), axis=1)
    order = np.lexsort((pairs[:, 1], pairs[:, 0]))
    return pairs[order]


def expand_rows(indptr: np.ndarray, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pair every entry of ``rows`` with every entry of that row of a CSR structure.

    Returns ``(which, entry)``: for each ``r = rows[q]`` and each ``e`` in
    ``indptr[r]:indptr[r + 1]``, one element ``which = q`` and ``entry = e``.
    Vectorised, ``O(sum of row lengths)``; used to scan neighbours of neighbours.
    """
    rows = np.asarray(rows, dtype=np.intp)
    counts = indptr[rows + 1] - indptr[rows]
    which = np.repeat(np.arange(len(rows)), counts)
    offsets = np.arange(counts.sum()) - np.repeat(np.cumsum(counts) - counts, counts)
    return which, np.repeat(indptr[rows], counts) + offsets


def adjacency(n: int, pairs: np.ndarray, weights: np.ndarray | None = None) -> sp.csr_matrix:
    """Symmetric sparse adjacency matrix of an undirected (weighted) graph."""
    pairs = np.asarray(pairs, dtype=np.intp).reshape(-1, 2)
    w = np.ones(len(pairs)) if weights is None else np.asarray(weights, dtype=float)
    rows = np.concatenate([pairs[:, 0], pairs[:, 1]])
    cols = np.concatenate([pairs[:, 1], pairs[:, 0]])
    return sp.csr_matrix((np.concatenate([w, w]), (rows, cols)), shape=(n, n))


def laplacian(n: int, pairs: np.ndarray, weights: np.ndarray | None = None) -> sp.csr_matrix:
    """Graph Laplacian ``L = D - A`` (weighted if ``weights`` is given)."""
    a = adjacency(n, pairs, weights)
    degree = np.asarray(a.sum(axis=1)).ravel()
    return (sp.diags(degree) - a).tocsr()


def laplacian_dense(n: int, pairs: np.ndarray, weights: np.ndarray | None = None) -> np.ndarray:
    """Dense ``(n, n)`` Laplacian ``L = diag(W 1) - W`` (links with zero weight included).

    The one dense builder of the package: every dense eigensolver in tether
    factors exactly this matrix, so two callers on the same graph get the
    same bits.
    """
    pairs = np.asarray(pairs, dtype=np.intp).reshape(-1, 2)
    w = np.ones(len(pairs)) if weights is None else np.asarray(weights, dtype=float)
    lap = np.zeros((n, n))
    i, j = pairs[:, 0], pairs[:, 1]
    lap[i, j] = -w
    lap[j, i] = -w
    lap[np.diag_indices(n)] = -lap.sum(axis=1)
    return lap


#: up to this many nodes :func:`components` labels by union-find (scipy's numbering):
#: building the sparse matrix costs ten times the search there
SMALL_COMPONENTS_N = 64


def components(n: int, pairs: np.ndarray) -> tuple[int, np.ndarray]:
    """Number of connected components and the component label of each robot."""
    if n == 0:
        return 0, np.empty(0, dtype=np.intp)
    pairs = np.asarray(pairs, dtype=np.intp).reshape(-1, 2)
    if n <= SMALL_COMPONENTS_N and (len(pairs) == 0 or (pairs.min() >= 0 and pairs.max() < n)):
        return _small_components(n, pairs)
    count, labels = connected_components(adjacency(n, pairs), directed=False)
    return int(count), labels


def _small_components(n: int, pairs: np.ndarray) -> tuple[int, np.ndarray]:
    """:func:`components` by union-find, labels numbered by each component's first node
    (as ``scipy.sparse.csgraph.connected_components`` numbers them; tested)."""
    parent = list(range(n))

    def root(x: int) -> int:
        while parent[x] != x:
            parent[x] = parent[parent[x]]
            x = parent[x]
        return x

    for a, b in pairs.tolist():
        ra, rb = root(a), root(b)
        if ra != rb:
            parent[max(ra, rb)] = min(ra, rb)
    labels = np.empty(n, dtype=np.int32)
    first: dict[int, int] = {}
    for v in range(n):
        labels[v] = first.setdefault(root(v), len(first))
    return len(first), labels


def component_count(n: int, pairs: np.ndarray) -> int:
    """Number of connected components (:func:`components` without the labels)."""
    if n == 0:
        return 0
    if jit.warm():
        from tether.graph.kernels import component_count_kernel

        return int(component_count_kernel(n, np.asarray(pairs, dtype=np.int64).reshape(-1, 2)))
    return components(n, pairs)[0]


def is_connected(n: int, pairs: np.ndarray) -> bool:
    """True iff the graph on ``n`` robots is connected (a single robot is)."""
    return n <= 1 or components(n, pairs)[0] == 1


def stretch(positions: np.ndarray, pairs: np.ndarray) -> float:
    """Geometric stretch (dilation) of the graph.

    The largest ratio, over all robot pairs, of the shortest path length
    through links (Euclidean edge lengths) to the straight-line distance.
    ``inf`` if the graph is disconnected, 1.0 for a complete graph. Cost
    ``O(n (m + n log n))``; meant for analysis, not for hot loops.
    """
    positions = np.asarray(positions, dtype=float)
    n = len(positions)
    if n < 2:
        return 1.0
    pairs = np.asarray(pairs, dtype=np.intp).reshape(-1, 2)
    lengths = np.linalg.norm(positions[pairs[:, 0]] - positions[pairs[:, 1]], axis=1)
    graph_dist = dijkstra(adjacency(n, pairs, np.maximum(lengths, 1e-12)), directed=False)
    euclid = np.linalg.norm(positions[:, None, :] - positions[None, :, :], axis=-1)
    off = ~np.eye(n, dtype=bool) & (euclid > 0)
    if not np.all(np.isfinite(graph_dist[off])):
        return float("inf")
    return float(np.max(graph_dist[off] / euclid[off]))
