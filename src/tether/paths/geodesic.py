"""Geodesic distances and paths on a coarsened known-free grid.

The exploration graph of the recurrent-connectivity paper (Banfi et al.,
Sec. III) carries "an estimate of the geodesic distance" ``d_ij`` between
vertices, and robots travel along known free space. A coarse cell (a block of
``factor x factor`` fine cells) is traversable when *all* its fine cells are
known free -- a conservative inflation that also keeps a robot body away from
walls. Coarse cells are joined 8-connected (diagonals only when both
orthogonal neighbours are traversable, so no corner is cut), with Euclidean
step costs in fine cells. Distances and paths come from
``scipy.sparse.csgraph.dijkstra`` (the reference) or, with the compiled kernels
on (:mod:`tether.jit`), from a bucket-queue Dijkstra on the grid itself
(:mod:`tether.paths.geodesic_kernels`): the same distances bit for bit and the same
paths (:class:`Geodesics`), about five times faster.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
from scipy import ndimage
from scipy.sparse.csgraph import dijkstra

from tether import jit

__all__ = ["CoarseGrid", "Geodesics"]


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
        self.n_nodes = len(cells)
        self._graph: sp.csr_matrix | None = None
        self._components: np.ndarray | None = None
        self._kernel_view: tuple[np.ndarray, np.ndarray, float, float] | None = None

    @property
    def graph(self) -> sp.csr_matrix:
        """The weighted adjacency (CSR, symmetric) of the nodes, built on first use."""
        if self._graph is None:
            self._graph = self._build_graph()
        return self._graph

    def _build_graph(self) -> sp.csr_matrix:
        """Edges of the 8-connected grid, each stored in both directions with one weight."""
        blocks, node, f = self.traversable, self.node, self.factor
        cx, cy = self.shape
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
        n = self.n_nodes
        return sp.csr_matrix((np.r_[v, v], (np.r_[r, c], np.r_[c, r])), shape=(n, n))

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
        """Connected-component label of every node, numbered by their first node.

        ``scipy.sparse.csgraph.connected_components``' labels of :attr:`graph`: a
        diagonal edge needs both orthogonal cells, so the components are the
        4-connected ones of :attr:`traversable`, which ``ndimage.label`` numbers in
        raster order -- the order of the nodes' ids, as scipy does.
        """
        if self._components is None:
            lab, _ = ndimage.label(self.traversable)
            self._components = lab[self.cells[:, 0], self.cells[:, 1]].astype(np.int32) - 1
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
        """Geodesic distances (fine cells) from each source node to every node, ``(k, n)``.

        With ``predecessors`` also scipy's predecessor matrix (:meth:`geodesics` gives
        the same paths faster). The distances are the same bits either way.
        """
        sources = np.atleast_1d(np.asarray(sources, dtype=np.intp))
        if len(sources) == 0:
            empty = np.empty((0, self.n_nodes))
            return (empty, empty.astype(np.intp)) if predecessors else empty
        if not predecessors and jit.enabled():
            return self._kernel(sources, False)[0]
        return self._scipy(sources, predecessors)

    def geodesics(self, sources: np.ndarray, lazy: bool = False) -> Geodesics:
        """Distances from each source node and the paths to any node (:class:`Geodesics`).

        The paths are those of scipy's predecessors (:meth:`distances`), whichever
        implementation runs (:mod:`tether.jit`). With ``lazy`` and the kernels on, no
        predecessor matrix is made: :meth:`Geodesics.path` derives each path asked for
        from the distances (the same path; a caller that needs a few paths saves the
        predecessor pass over every node of every source).
        """
        sources = np.atleast_1d(np.asarray(sources, dtype=np.intp))
        if len(sources) and jit.enabled():
            if lazy:
                return Geodesics(self, sources, self._kernel(sources, False)[0], None, None)
            dist, pred, tie = self._kernel(sources, True)
        else:
            dist, pred = self.distances(sources, predecessors=True)
            tie = np.zeros(pred.shape, dtype=bool)
        return Geodesics(self, sources, dist, pred, tie)

    def _scipy(self, sources: np.ndarray, predecessors: bool) -> np.ndarray | tuple:
        """The reference: scipy's Dijkstra (Fibonacci heap) on :attr:`graph`.

        ``directed=True`` on the symmetric graph gives the same result as
        ``directed=False`` (which scans every edge twice, the second time without
        effect) in half the time.
        """
        return dijkstra(self.graph, directed=True, indices=sources,
                        return_predecessors=predecessors)  # fmt: skip

    def _kernel(self, sources: np.ndarray, predecessors: bool) -> tuple[np.ndarray, ...]:
        """:func:`~tether.paths.geodesic_kernels.grid_dijkstra_kernel` in node ids."""
        from tether.paths.geodesic_kernels import grid_dijkstra_kernel

        return grid_dijkstra_kernel(*self._kernel_grid(), sources, predecessors)

    def _kernel_grid(self) -> tuple[np.ndarray, np.ndarray, float, float]:
        """The kernels' view of the grid: padded mask, raveled node cells, edge weights.

        Made once per grid (every search and every traced path reads it).
        """
        if self._kernel_view is None:
            cx, cy = self.shape
            padded = np.zeros((cx + 2, cy + 2), dtype=bool)
            padded[1:-1, 1:-1] = self.traversable
            flat = (self.cells[:, 0] + 1) * (cy + 2) + self.cells[:, 1] + 1
            w_orth, w_diag = self.factor * 1.0, self.factor * np.sqrt(2.0)  # as _build_graph
            self._kernel_view = (padded, flat, w_orth, w_diag)
        return self._kernel_view

    def path(self, pred_row: np.ndarray, target: int) -> np.ndarray:
        """Fine waypoints from the Dijkstra source to ``target`` (source included)."""
        return self.centre(_trace(pred_row, target))


def _trace(pred_row: np.ndarray, target: int) -> np.ndarray:
    """Nodes from the source of ``pred_row`` to ``target`` (both included)."""
    nodes = [int(target)]
    while pred_row[nodes[-1]] >= 0:
        nodes.append(int(pred_row[nodes[-1]]))
    return np.asarray(nodes[::-1], dtype=np.intp)


@dataclass
class Geodesics:
    """Shortest paths from ``sources`` (node ids) of a :class:`CoarseGrid`.

    ``dist`` and ``pred`` are ``(k, n)`` like :meth:`CoarseGrid.distances`' output.
    ``tie[i, x]``: ``pred[i, x]`` was not decided by the distances alone (two
    neighbours with the same smallest label lead to ``x``,
    :mod:`tether.paths.geodesic_kernels`); a path through such a node is taken from
    scipy's predecessors of that source instead, so :meth:`path` always returns
    scipy's path.
    """

    grid: CoarseGrid
    sources: np.ndarray
    dist: np.ndarray
    pred: np.ndarray | None
    """``None`` when made ``lazy`` (:meth:`CoarseGrid.geodesics`): paths from ``dist``."""
    tie: np.ndarray | None

    def path(self, row: int, target: int) -> np.ndarray:
        """Fine waypoints from source ``row`` to node ``target`` (the source included)."""
        if self.pred is None:
            from tether.paths.geodesic_kernels import trace_kernel

            nodes, tie = trace_kernel(*self.grid._kernel_grid(), self.dist[row], int(target))
            if not tie:
                return self.grid.centre(nodes)
            _, pred = self.grid.distances(self.sources[row : row + 1], predecessors=True)
            return self.grid.centre(_trace(pred[0], target))
        nodes = _trace(self.pred[row], target)
        if self.tie[row, nodes].any():
            _, pred = self.grid.distances(self.sources[row : row + 1], predecessors=True)
            self.pred[row] = pred[0]
            self.tie[row] = False
            nodes = _trace(self.pred[row], target)
        return self.grid.centre(nodes)
