"""The exploration graph ``G^t = (V^t, C^t)`` known by the base station.

Recurrent-connectivity paper (Banfi et al., Sec. III and VII): vertices are
the BS ``b``, the current frontier vertices ``F^t`` (one per sufficiently big
cluster of frontier cells) and visited locations (reached goals, "candidate
relay locations for future plans"); each pair carries a geodesic distance
estimate ``d_ij``; ``C^t`` holds the pairs that the link-detection mechanism
accepts on the BS's known map.

Vertices sit on centres of traversable coarse cells (see
:mod:`tether.recurrent.geodesic`); a frontier cluster's vertex is the
reachable coarse cell within one coarse cell of the cluster that is closest
to its centroid. The information gain ``g(f)`` is the number of unknown cells
within sensor range (a square window) of the vertex. Communication edges are
cached across plans: the known map only grows, so a link once detected stays
(and, for models that can tell, a pair blocked by a known obstacle stays
blocked).
"""

from __future__ import annotations

from dataclasses import dataclass

import networkx as nx
import numpy as np

from tether import jit
from tether.paths.geodesic import CoarseGrid
from tether.recurrent.planning.frontiers import FrontierCluster, frontier_clusters
from tether.sensing.links import LinkModel

__all__ = [
    "BASE",
    "FRONTIER",
    "RELAY",
    "ExplorationGraph",
    "GraphBuilder",
    "frontier_nodes",
    "snap_cluster",
    "window_counts",
]

BASE, FRONTIER, RELAY = 0, 1, 2


@dataclass
class ExplorationGraph:
    """``G^t``: vertex 0 is the BS; ``kind`` is BASE, FRONTIER or RELAY per vertex."""

    positions: np.ndarray  # (V, 2) cell coordinates of vertices
    nodes: np.ndarray  # (V,) coarse node ids
    kind: np.ndarray  # (V,) int
    gain: np.ndarray  # (V,) g(f), 0 for non-frontiers
    edges: np.ndarray  # (E, 2) communication edges C^t, i < j
    coarse: CoarseGrid

    @property
    def n(self) -> int:
        return len(self.positions)

    @property
    def frontiers(self) -> np.ndarray:
        return np.flatnonzero(self.kind == FRONTIER)

    def vertex_of_node(self, node: int) -> int:
        """Index of the vertex on coarse node ``node`` (``-1`` if none)."""
        hit = np.flatnonzero(self.nodes == node)
        return int(hit[0]) if len(hit) else -1

    def vertices_of_nodes(self, nodes: np.ndarray) -> np.ndarray:
        """:meth:`vertex_of_node` of each node of ``nodes`` (vertices sit on distinct nodes)."""
        nodes = np.asarray(nodes, dtype=np.intp)
        if self.n == 0:
            return np.full(len(nodes), -1, dtype=np.intp)
        order = np.argsort(self.nodes, kind="stable")
        at = np.minimum(np.searchsorted(self.nodes[order], nodes), self.n - 1)
        return np.where(self.nodes[order][at] == nodes, order[at], -1)

    def geodesic(self, points: np.ndarray) -> np.ndarray:
        """Geodesic distance estimates (cells) from each point to every vertex, ``(k, V)``."""
        src = self.coarse.node_at(points)
        out = np.full((len(src), self.n), np.inf)
        ok = src >= 0
        if ok.any():
            d = self.coarse.distances(src[ok])
            out[ok] = d[:, self.nodes]
        return out

    def to_networkx(self) -> nx.Graph:
        """``G^t`` as an undirected networkx graph on vertex ids ``0..V-1``.

        Node attributes: ``pos``, ``kind`` ("base", "frontier", "relay"), ``gain``.
        """
        g = nx.Graph()
        names = {BASE: "base", FRONTIER: "frontier", RELAY: "relay"}
        for v in range(self.n):
            g.add_node(
                v,
                pos=tuple(self.positions[v]),
                kind=names[int(self.kind[v])],
                gain=float(self.gain[v]),
            )
        g.add_edges_from(map(tuple, self.edges.tolist()))
        return g


def window_counts(mask: np.ndarray, points: np.ndarray, half_width: int) -> np.ndarray:
    """Number of true cells of ``mask`` in the square window of half width around each point."""
    if jit.enabled():  # the same counts, compiled
        from tether.recurrent.planning.expgraph_kernels import window_counts_kernel

        pts = np.ascontiguousarray(np.atleast_2d(points), dtype=float)
        return window_counts_kernel(np.ascontiguousarray(mask, dtype=bool), pts, int(half_width))
    c = np.floor(np.atleast_2d(points)).astype(np.intp)
    nx_, ny_ = mask.shape
    x0 = np.clip(c[:, 0] - half_width, 0, nx_)
    x1 = np.clip(c[:, 0] + half_width + 1, 0, nx_)
    y0 = np.clip(c[:, 1] - half_width, 0, ny_)
    y1 = np.clip(c[:, 1] + half_width + 1, 0, ny_)
    if len(c) * (2 * half_width + 1) ** 2 < mask.size:  # few small windows: sum directly
        return np.array(
            [np.count_nonzero(mask[a:b, e:f]) for a, b, e, f in zip(x0, x1, y0, y1, strict=True)],
            dtype=np.int64,
        )
    ii = np.zeros((nx_ + 1, ny_ + 1), dtype=np.int64)
    ii[1:, 1:] = np.cumsum(np.cumsum(mask, axis=0), axis=1)
    return ii[x1, y1] - ii[x0, y1] - ii[x1, y0] + ii[x0, y0]


def snap_cluster(cluster: FrontierCluster, coarse: CoarseGrid, allowed: np.ndarray) -> int:
    """Allowed coarse node within one coarse cell of the cluster closest to its centroid."""
    w = coarse.shape[1] + 2
    cc = cluster.cells // coarse.factor
    cc = np.unique((cc[:, 0] + 1) * w + (cc[:, 1] + 1))  # 1-D keys are much faster
    off = np.array([dx * w + dy for dx in (-1, 0, 1) for dy in (-1, 0, 1)])
    keys = np.unique((cc[:, None] + off[None]).ravel())
    cand = np.stack([keys // w - 1, keys % w - 1], axis=1)
    ok = (
        (cand[:, 0] >= 0)
        & (cand[:, 0] < coarse.shape[0])
        & (cand[:, 1] >= 0)
        & (cand[:, 1] < coarse.shape[1])
    )
    cand = cand[ok]
    nodes = coarse.node[cand[:, 0], cand[:, 1]]
    nodes = nodes[nodes >= 0]
    nodes = nodes[allowed[nodes]]
    if len(nodes) == 0:
        return -1
    d = np.linalg.norm(coarse.centre(nodes) - cluster.centroid, axis=1)
    return int(nodes[np.argmin(d)])


def frontier_nodes(
    known: np.ndarray,
    occupied: np.ndarray,
    coarse: CoarseGrid,
    allowed: np.ndarray,
    min_cells: int,
    max_extent_cells: int,
) -> list[int]:
    """The snapped node of every frontier cluster of ``known``, in cluster order (-1: none).

    :func:`~tether.recurrent.planning.frontiers.frontier_clusters`, then
    :func:`snap_cluster` on each; with the kernels on, one compiled pass giving the
    same nodes (:mod:`tether.recurrent.planning.expgraph_kernels`).
    """
    if jit.enabled():
        from tether.recurrent.planning.expgraph_kernels import frontier_nodes_kernel

        nodes, _ = frontier_nodes_kernel(
            np.ascontiguousarray(known, dtype=bool),
            np.ascontiguousarray(occupied, dtype=bool),
            int(min_cells),
            int(max_extent_cells),
            coarse.node,
            coarse.factor,
            np.ascontiguousarray(allowed, dtype=bool),
        )
        return nodes.tolist()
    clusters = frontier_clusters(known, occupied, min_cells, max_extent_cells)
    return [snap_cluster(c, coarse, allowed) for c in clusters]


class GraphBuilder:
    """Builds ``G^t`` from the BS's known map, caching communication edges across plans.

    Parameters
    ----------
    occupied
        True occupancy grid (read only where known).
    link_model
        A link model from :data:`tether.registry.LINK_MODELS`.
    coarse_factor
        Coarsening of the geodesic grid.
    gain_half_width
        Half width (cells) of the window counting unknown cells for ``g(f)``
        (the sensor range).
    min_cluster_cells, max_cluster_extent
        Frontier clustering (see :func:`tether.recurrent.frontiers.cluster_frontiers`).
    """

    def __init__(
        self,
        occupied: np.ndarray,
        link_model: LinkModel,
        coarse_factor: int = 3,
        gain_half_width: int = 50,
        min_cluster_cells: int = 4,
        max_cluster_extent: int = 30,
    ) -> None:
        self.occupied = np.asarray(occupied, dtype=bool)
        self.link_model = link_model
        self.coarse_factor = int(coarse_factor)
        self.gain_half_width = int(gain_half_width)
        self.min_cluster_cells = int(min_cluster_cells)
        self.max_cluster_extent = int(max_cluster_extent)
        self._linked = _KeySet()  # cell-key pairs known to link
        self._blocked = _KeySet()  # ... and those no growth of the known map can link

    def coarse_grid(self, known: np.ndarray) -> CoarseGrid:
        return CoarseGrid(known & ~self.occupied, self.coarse_factor)

    def build(
        self,
        known: np.ndarray,
        base: np.ndarray,
        relays: np.ndarray,
        coarse: CoarseGrid | None = None,
    ) -> ExplorationGraph:
        """``G^t`` for the known map ``known``.

        Parameters
        ----------
        known
            BS known-cell mask.
        base
            BS position (cell coordinates; must lie on a traversable coarse cell).
        relays
            ``(m, 2)`` positions of visited / assigned locations (vertices that
            are not frontiers unless a frontier snaps onto them).
        """
        known = np.asarray(known, dtype=bool)
        coarse = coarse if coarse is not None else self.coarse_grid(known)
        base_node = int(coarse.node_at(base)[0])
        if base_node < 0:
            raise ValueError("the base station is not on a traversable known cell")
        comp = coarse.components
        allowed = comp == comp[base_node]
        relay_nodes = coarse.node_at(np.asarray(relays, dtype=float).reshape(-1, 2))
        relay_nodes = relay_nodes[(relay_nodes >= 0) & (relay_nodes != base_node)]
        relay_nodes = list(dict.fromkeys(relay_nodes.tolist()))
        nodes = [base_node, *relay_nodes]
        kind = [BASE] + [RELAY] * len(relay_nodes)
        index = {nd: i for i, nd in enumerate(nodes)}
        for nd in frontier_nodes(
            known, self.occupied, coarse, allowed, self.min_cluster_cells, self.max_cluster_extent
        ):
            if nd < 0 or nd == base_node:
                continue
            if nd in index:
                kind[index[nd]] = FRONTIER
            else:
                index[nd] = len(nodes)
                nodes.append(nd)
                kind.append(FRONTIER)
        nodes_arr = np.asarray(nodes, dtype=np.intp)
        kind_arr = np.asarray(kind, dtype=np.int8)
        positions = coarse.centre(nodes_arr)
        gain = np.zeros(len(nodes_arr))
        fr = kind_arr == FRONTIER
        if fr.any():
            gain[fr] = window_counts(~known, positions[fr], self.gain_half_width)
        cells = coarse.cells[nodes_arr]
        edges = self._edges(known, cells[:, 0] * (coarse.shape[1] + 1) + cells[:, 1], positions)
        return ExplorationGraph(positions, nodes_arr, kind_arr, gain, edges, coarse)

    def _edges(self, known: np.ndarray, keys_: np.ndarray, positions: np.ndarray) -> np.ndarray:
        # keys_ are coarse *cell* keys (stable while the known map grows; node ids are not)
        nodes = keys_
        i, j = pairs_in_range(positions, self.link_model.range_cells)
        if len(i) == 0:
            return np.empty((0, 2), dtype=np.intp)
        lo = np.minimum(nodes[i], nodes[j]).astype(np.int64)
        hi = np.maximum(nodes[i], nodes[j]).astype(np.int64)
        keys = lo * PAIR_BASE + hi
        linked = self._linked.contains(keys)
        blocked = self._blocked.contains(keys)
        todo = np.flatnonzero(~linked & ~blocked)
        if len(todo):
            free = known & ~self.occupied
            ok = self.link_model.linked(free, positions[i[todo]], positions[j[todo]])
            linked[todo] = ok
            self._linked.add(keys[todo[ok]])
            never = getattr(self.link_model, "blocked_forever", None)
            rest = todo[~ok]
            if never is not None and len(rest):
                hard = never(known & self.occupied, positions[i[rest]], positions[j[rest]])
                self._blocked.add(keys[rest[hard]])
        return np.stack([i[linked], j[linked]], axis=1)


def pairs_in_range(positions: np.ndarray, range_cells: float) -> tuple[np.ndarray, np.ndarray]:
    """Vertex pairs ``i < j`` with ``norm(positions[i] - positions[j]) <= range_cells``.

    In the order of ``np.triu_indices`` (row by row) and with the same distances
    (``sqrt(dx * dx + dy * dy)``, as ``np.linalg.norm`` sums the squares), from one
    ``(V, V)`` matrix instead of a gather per pair.
    """
    dx = positions[:, 0][:, None] - positions[:, 0][None, :]
    dy = positions[:, 1][:, None] - positions[:, 1][None, :]
    close = np.sqrt(dx * dx + dy * dy) <= range_cells
    return np.nonzero(np.triu(close, 1))


#: a pair of coarse cell keys ``lo < hi`` is cached as ``lo * PAIR_BASE + hi``
PAIR_BASE = 1 << 31


class _KeySet:
    """A growing set of ``int64`` keys, kept sorted for vectorised membership tests."""

    def __init__(self) -> None:
        self.keys = np.empty(0, dtype=np.int64)

    def __len__(self) -> int:
        return len(self.keys)

    def contains(self, keys: np.ndarray) -> np.ndarray:
        """Boolean, per key: in the set."""
        if len(self.keys) == 0:
            return np.zeros(len(keys), dtype=bool)
        at = np.minimum(np.searchsorted(self.keys, keys), len(self.keys) - 1)
        return self.keys[at] == keys

    def add(self, keys: np.ndarray) -> None:
        """Insert ``keys`` (duplicates and keys already present are fine).

        The new keys are sorted alone and inserted into the sorted set in one pass
        (``np.union1d`` sorted the whole set again at every call: the set grows to the
        pairs of a whole run, the keys added per plan are a few).
        """
        if len(keys):
            new = np.unique(np.asarray(keys, dtype=np.int64))
            new = new[~self.contains(new)]
            if len(new):
                self.keys = np.insert(self.keys, np.searchsorted(self.keys, new), new)
