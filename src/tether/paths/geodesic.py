"""Geodesic distances and paths on a coarsened known-free grid.

The exploration graph of the recurrent-connectivity paper (Banfi et al.,
Sec. III) carries "an estimate of the geodesic distance" ``d_ij`` between
vertices, and robots travel along known free space. A coarse cell (a block of
``factor x factor`` fine cells) is traversable when *all* its fine cells are
known free -- a conservative inflation that also keeps a robot body away from
walls. Coarse cells are joined 8-connected (diagonals only when both
orthogonal neighbours are traversable, so no corner is cut), with Euclidean
step costs in fine cells; distances come from ``scipy.sparse.csgraph.dijkstra``
from many sources at once.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import connected_components, dijkstra

__all__ = ["CoarseGrid"]


class CoarseGrid:
    """8-connected graph of traversable coarse cells of a free mask.

    Parameters
    ----------
    free
        ``(nx, ny)`` boolean mask of cells considered free (e.g. known free).
    factor
        Coarsening factor (odd values put coarse centres on fine cell centres).
    """

    def __init__(self, free: np.ndarray, factor: int = 3) -> None:
        free = np.asarray(free, dtype=bool)
        f = int(factor)
        self.factor = f
        self.fine_shape = free.shape
        cx, cy = free.shape[0] // f, free.shape[1] // f
        self.shape = (cx, cy)
        crop = free[: cx * f, : cy * f]
        rows = crop[0::f]
        for k in range(1, f):
            rows = rows & crop[k::f]
        blocks = rows[:, 0::f]
        for k in range(1, f):
            blocks = blocks & rows[:, k::f]
        self.traversable = blocks
        node = np.full((cx, cy), -1, dtype=np.intp)
        cells = np.argwhere(blocks)
        node[cells[:, 0], cells[:, 1]] = np.arange(len(cells))
        self.node = node
        self.cells = cells
        rows, cols, vals = [], [], []
        for dx, dy in ((1, 0), (0, 1), (1, 1), (1, -1)):
            # cell (x, y) -> (x + dx, y + dy), both traversable
            ya0, yb0 = max(-dy, 0), max(dy, 0)
            ny_ = cy - abs(dy)
            nx_ = cx - dx
            here = blocks[:nx_, ya0 : ya0 + ny_]
            there = blocks[dx : dx + nx_, yb0 : yb0 + ny_]
            ok = here & there
            if dx and dy:  # diagonal: both orthogonal neighbours traversable (no corner cut)
                ok &= blocks[dx : dx + nx_, ya0 : ya0 + ny_] & blocks[:nx_, yb0 : yb0 + ny_]
            ia = np.argwhere(ok)
            rows.append(node[ia[:, 0], ia[:, 1] + ya0])
            cols.append(node[ia[:, 0] + dx, ia[:, 1] + yb0])
            vals.append(np.full(len(ia), f * (np.sqrt(2.0) if dx and dy else 1.0)))
        r = np.concatenate(rows)
        c = np.concatenate(cols)
        v = np.concatenate(vals)
        n = len(cells)
        self.n_nodes = n
        self.graph = sp.csr_matrix((np.r_[v, v], (np.r_[r, c], np.r_[c, r])), shape=(n, n))
        self._components: np.ndarray | None = None

    # ------------------------------------------------------------------ lookups
    def node_at(self, points: np.ndarray) -> np.ndarray:
        """Node id of the coarse cell containing each point (``-1`` if not traversable)."""
        pts = np.atleast_2d(np.asarray(points, dtype=float))
        c = np.floor(pts / self.factor).astype(np.intp)
        ok = (c[:, 0] >= 0) & (c[:, 0] < self.shape[0]) & (c[:, 1] >= 0) & (c[:, 1] < self.shape[1])
        out = np.full(len(pts), -1, dtype=np.intp)
        out[ok] = self.node[c[ok, 0], c[ok, 1]]
        return out

    def centre(self, nodes: np.ndarray) -> np.ndarray:
        """Fine cell coordinates of coarse node centres, ``(k, 2)``."""
        nodes = np.atleast_1d(np.asarray(nodes, dtype=np.intp))
        return (self.cells[nodes] + 0.5) * self.factor

    @property
    def components(self) -> np.ndarray:
        """Connected-component label of every node."""
        if self._components is None:
            _, self._components = connected_components(self.graph, directed=False)
        return self._components

    def nearest_node(self, point: np.ndarray, radius_cells: float = np.inf) -> int:
        """Traversable node whose centre is closest (Euclidean) to ``point``, or -1."""
        if self.n_nodes == 0:
            return -1
        d = np.linalg.norm(self.centre(np.arange(self.n_nodes)) - np.asarray(point), axis=1)
        k = int(np.argmin(d))
        return k if d[k] <= radius_cells else -1

    # ------------------------------------------------------------------ distances
    def distances(
        self, sources: np.ndarray, predecessors: bool = False
    ) -> np.ndarray | tuple[np.ndarray, np.ndarray]:
        """Geodesic distances (fine cells) from each source node to every node, ``(k, n)``."""
        sources = np.atleast_1d(np.asarray(sources, dtype=np.intp))
        if len(sources) == 0:
            empty = np.empty((0, self.n_nodes))
            return (empty, empty.astype(np.intp)) if predecessors else empty
        return dijkstra(
            self.graph, directed=False, indices=sources, return_predecessors=predecessors
        )

    def path(self, pred_row: np.ndarray, target: int) -> np.ndarray:
        """Fine waypoints from the Dijkstra source to ``target`` (source included)."""
        nodes = [int(target)]
        while pred_row[nodes[-1]] >= 0:
            nodes.append(int(pred_row[nodes[-1]]))
        return self.centre(np.asarray(nodes[::-1]))
