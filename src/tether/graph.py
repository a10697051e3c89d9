"""Interaction graphs of a team: links, Laplacians, lambda2, components, stretch.

A graph on ``n`` robots is given by an ``(m, 2)`` integer array of undirected
links ``pairs`` (``i < j``) and optional ``(m,)`` positive weights. Everything
here works on sparse matrices so that 10,000-robot teams stay cheap; dense
eigensolvers are used for small teams where they are faster and exact.

The algebraic connectivity lambda2 (Fiedler 1973) is the second-smallest
eigenvalue of the Laplacian ``L = D - A``; it is positive iff the graph is
connected. Its eigenvector is the Fiedler vector.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components, dijkstra
from scipy.spatial import cKDTree

DENSE_MAX_N = 400  # below this, a dense eigh is faster than a sparse solver


def pairs_within(positions: np.ndarray, range_m: float) -> np.ndarray:
    """All pairs ``(i, j)``, ``i < j``, with ``||p_i - p_j|| <= range_m``.

    Uses a k-d tree, so the cost is ``O(n log n + m)`` rather than all-pairs.
    """
    positions = np.asarray(positions, dtype=float)
    if len(positions) < 2:
        return np.empty((0, 2), dtype=np.intp)
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


def components(n: int, pairs: np.ndarray) -> tuple[int, np.ndarray]:
    """Number of connected components and the component label of each robot."""
    if n == 0:
        return 0, np.empty(0, dtype=np.intp)
    count, labels = connected_components(adjacency(n, pairs), directed=False)
    return int(count), labels


def is_connected(n: int, pairs: np.ndarray) -> bool:
    """True iff the graph on ``n`` robots is connected (a single robot is)."""
    return n <= 1 or components(n, pairs)[0] == 1


def fiedler(
    n: int,
    pairs: np.ndarray,
    weights: np.ndarray | None = None,
    *,
    method: Literal["auto", "dense", "sparse"] = "auto",
) -> tuple[float, np.ndarray]:
    """Algebraic connectivity lambda2 and a unit Fiedler vector.

    Parameters
    ----------
    n, pairs, weights
        The graph (see module docstring).
    method
        ``"dense"``: ``numpy.linalg.eigh`` on the full Laplacian, ``O(n^3)``.
        ``"sparse"``: shift-invert Lanczos (``scipy.sparse.linalg.eigsh``) on
        ``L + sigma I``, about ``O(m)`` per iteration plus one sparse LU.
        ``"auto"``: dense up to ``DENSE_MAX_N`` robots.

    Returns
    -------
    lambda2, vector
        ``lambda2 >= 0``; it is exactly 0 for a disconnected graph, in which
        case the vector is a normalised, zero-mean component indicator.
    """
    if n < 2:
        return 0.0, np.zeros(n)
    if method == "auto":
        method = "dense" if n <= DENSE_MAX_N else "sparse"
    lap = laplacian(n, pairs, weights)
    if method == "dense":
        vals, vecs = np.linalg.eigh(lap.toarray())
        return max(float(vals[1]), 0.0), vecs[:, 1]
    count, labels = components(n, pairs)
    if count > 1:
        v = (labels == labels[0]).astype(float)
        v -= v.mean()
        return 0.0, v / np.linalg.norm(v)
    from scipy.sparse.linalg import eigsh

    sigma = -1e-3
    vals, vecs = eigsh(lap.tocsc(), k=2, sigma=sigma, which="LM")
    order = np.argsort(vals)
    return max(float(vals[order[1]]), 0.0), vecs[:, order[1]]


def algebraic_connectivity(
    n: int,
    pairs: np.ndarray,
    weights: np.ndarray | None = None,
    *,
    method: Literal["auto", "dense", "sparse"] = "auto",
) -> float:
    """lambda2 of the (weighted) Laplacian; see :func:`fiedler`."""
    return fiedler(n, pairs, weights, method=method)[0]


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
