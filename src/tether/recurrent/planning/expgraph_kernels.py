"""Compiled kernels of the exploration graph's vertices (numba; imported only when used).

:func:`frontier_nodes_kernel` does in one pass what
:func:`tether.recurrent.planning.frontiers.frontier_clusters` followed by
:func:`tether.recurrent.planning.expgraph.snap_cluster` per cluster do (the
reference): frontier cells (known free with an unknown 4-neighbour), their
8-connected components cut into tiles of ``max_extent`` cells, clusters of at least
``min_cells`` cells ordered by decreasing size then first cell, and each cluster's
vertex, the allowed coarse node within one coarse cell of the cluster closest to its
centroid. The arithmetic is the reference's (sums of integer coordinates are exact,
one division, the same squared differences summed in the same order, the first node
in id order on ties), so the nodes are the same (tests compare them).

:func:`window_counts_kernel` counts the true cells of a mask in square windows, as
:func:`tether.recurrent.planning.expgraph.window_counts` does.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def _frontier_mask(known, occupied):  # noqa: ANN001, ANN202
    """Known free cells with an unknown 4-neighbour inside the grid."""
    nx_, ny_ = known.shape
    out = np.zeros((nx_, ny_), np.bool_)
    for x in range(nx_):
        for y in range(ny_):
            if not known[x, y] or occupied[x, y]:
                continue
            if (
                (x > 0 and not known[x - 1, y])
                or (x + 1 < nx_ and not known[x + 1, y])
                or (y > 0 and not known[x, y - 1])
                or (y + 1 < ny_ and not known[x, y + 1])
            ):
                out[x, y] = True
    return out


@njit(cache=True)
def _components(mask):  # noqa: ANN001, ANN202
    """8-connected component label (from 0, in raster order of first cells) per true cell."""
    nx_, ny_ = mask.shape
    label = np.full((nx_, ny_), -1, np.int64)
    stack = np.empty(nx_ * ny_, np.int64)
    count = 0
    for x0 in range(nx_):
        for y0 in range(ny_):
            if not mask[x0, y0] or label[x0, y0] >= 0:
                continue
            label[x0, y0] = count
            stack[0] = x0 * ny_ + y0
            top = 1
            while top > 0:
                top -= 1
                x, y = divmod(stack[top], ny_)
                for dx in range(-1, 2):
                    for dy in range(-1, 2):
                        u, v = x + dx, y + dy
                        if 0 <= u < nx_ and 0 <= v < ny_ and mask[u, v] and label[u, v] < 0:
                            label[u, v] = count
                            stack[top] = u * ny_ + v
                            top += 1
            count += 1
    return label


@njit(cache=True)
def frontier_nodes_kernel(known, occupied, min_cells, max_extent, node, factor, allowed):  # noqa: ANN001, ANN201
    """The vertex (coarse node, ``-1`` if none) of each frontier cluster, in cluster order.

    ``node``: the coarse grid's node id per coarse cell (``-1`` if not traversable);
    ``allowed``: per node, whether a frontier may snap to it. Returns the nodes and
    the clusters' sizes.
    """
    nx_, ny_ = known.shape
    mask = _frontier_mask(known, occupied)
    label = _components(mask)
    ext = max(max_extent, 1)
    tiles_y = ny_ // ext + 1
    tiles = (nx_ // ext + 1) * tiles_y
    m = 0
    for x in range(nx_):
        for y in range(ny_):
            if mask[x, y]:
                m += 1
    key = np.empty(m, np.int64)
    cell = np.empty(m, np.int64)
    i = 0
    for x in range(nx_):
        for y in range(ny_):
            if mask[x, y]:
                key[i] = label[x, y] * tiles + (x // ext) * tiles_y + y // ext
                cell[i] = x * ny_ + y
                i += 1
    order = np.argsort(key, kind="mergesort")  # stable: raster order inside a group
    starts = []
    for j in range(m):
        if j == 0 or key[order[j]] != key[order[j - 1]]:
            starts.append(j)
    starts.append(m)
    n_groups = len(starts) - 1
    size = np.empty(n_groups, np.int64)
    first = np.empty(n_groups, np.int64)
    for g in range(n_groups):
        size[g] = starts[g + 1] - starts[g]
        first[g] = cell[order[starts[g]]]
    # by decreasing size, then first cell (the reference's sort of its clusters)
    rank = np.argsort(first - size * (nx_ * ny_ + 1), kind="mergesort")
    cx, cy = node.shape
    out = np.full(n_groups, -1, np.int64)
    sizes = np.empty(n_groups, np.int64)
    kept = 0
    for r in range(n_groups):
        g = rank[r]
        if size[g] < min_cells:
            continue
        sx = 0.0
        sy = 0.0
        for j in range(starts[g], starts[g + 1]):
            x, y = divmod(cell[order[j]], ny_)
            sx += x
            sy += y
        mx = sx / size[g] + 0.5
        my = sy / size[g] + 0.5
        best = -1
        best_d = np.inf
        for j in range(starts[g], starts[g + 1]):
            x, y = divmod(cell[order[j]], ny_)
            bx, by = x // factor, y // factor
            for ox in range(bx - 1, bx + 2):
                for oy in range(by - 1, by + 2):
                    if ox < 0 or ox >= cx or oy < 0 or oy >= cy:
                        continue
                    nd = node[ox, oy]
                    if nd < 0 or not allowed[nd]:
                        continue
                    ddx = (ox + 0.5) * factor - mx
                    ddy = (oy + 0.5) * factor - my
                    dist = math.sqrt(ddx * ddx + ddy * ddy)
                    if dist < best_d or (dist == best_d and nd < best):
                        best = nd
                        best_d = dist
        out[kept] = best
        sizes[kept] = size[g]
        kept += 1
    return out[:kept], sizes[:kept]


@njit(cache=True)
def window_counts_kernel(mask, points, half_width):  # noqa: ANN001, ANN201
    """True cells of ``mask`` in the square window of ``half_width`` around each point."""
    nx_, ny_ = mask.shape
    out = np.zeros(len(points), np.int64)
    for k in range(len(points)):
        x = int(math.floor(points[k, 0]))
        y = int(math.floor(points[k, 1]))
        x0, x1 = min(max(x - half_width, 0), nx_), min(max(x + half_width + 1, 0), nx_)
        y0, y1 = min(max(y - half_width, 0), ny_), min(max(y + half_width + 1, 0), ny_)
        c = 0
        for u in range(x0, x1):
            for v in range(y0, y1):
                if mask[u, v]:
                    c += 1
        out[k] = c
    return out


def warm_up() -> None:
    """Compile (or load from numba's cache) the kernels on a tiny map."""
    known = np.zeros((9, 9), dtype=bool)
    known[:5] = True
    occupied = np.zeros((9, 9), dtype=bool)
    node = np.arange(9).reshape(3, 3)
    frontier_nodes_kernel(known, occupied, 1, 30, node, 3, np.ones(9, dtype=bool))
    window_counts_kernel(known, np.array([[4.5, 4.5]]), 2)
