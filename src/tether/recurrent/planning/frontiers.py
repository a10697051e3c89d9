"""Frontier detection on a known map and clustering of frontier cells.

Recurrent-connectivity paper (Banfi et al., Sec. III and VII): frontiers are
free locations on the boundary between explored and unexplored space; the
exploration graph adds as vertices "locations representing a sufficiently big
cluster of frontier cells". Here a frontier cell is a known-free cell with a
4-neighbour that is unknown; frontier cells are grouped into 8-connected
components (``scipy.ndimage.label``), long components are cut into pieces no
larger than ``max_extent_cells`` along each axis, and pieces with fewer than
``min_cells`` cells are dropped.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

__all__ = ["FrontierCluster", "cluster_frontiers", "frontier_cells", "frontier_clusters"]

_SQUARE = ndimage.generate_binary_structure(2, 2)


def frontier_cells(known: np.ndarray, occupied: np.ndarray) -> np.ndarray:
    """Boolean mask of frontier cells: known free with an unknown 4-neighbour.

    Parameters
    ----------
    known
        ``(nx, ny)`` boolean, cells observed so far.
    occupied
        ``(nx, ny)`` boolean true occupancy (only read where ``known``).
    """
    known = np.asarray(known, dtype=bool)
    known_free = known & ~np.asarray(occupied, dtype=bool)
    unknown = ~known
    near = unknown.copy()  # 4-neighbour dilation by shifts (faster than ndimage here)
    near[1:] |= unknown[:-1]
    near[:-1] |= unknown[1:]
    near[:, 1:] |= unknown[:, :-1]
    near[:, :-1] |= unknown[:, 1:]
    return known_free & near


@dataclass
class FrontierCluster:
    """A group of frontier cells (``cells`` is ``(k, 2)`` integer ``(ix, iy)``)."""

    cells: np.ndarray

    @property
    def size(self) -> int:
        return len(self.cells)

    @property
    def centroid(self) -> np.ndarray:
        """Mean cell centre, in cell coordinates."""
        return self.cells.mean(axis=0) + 0.5


def cluster_frontiers(
    mask: np.ndarray, min_cells: int = 4, max_extent_cells: int = 30
) -> list[FrontierCluster]:
    """Cluster a frontier mask into groups (see module docstring).

    Clusters are returned by decreasing size (ties by position) so the output
    is deterministic.
    """
    labels, n = ndimage.label(mask, structure=_SQUARE)
    if n == 0:
        return []
    cells = np.argwhere(labels > 0)
    comp = labels[cells[:, 0], cells[:, 1]]
    # cut long components into tiles of max_extent_cells along each axis
    tile = cells // max(int(max_extent_cells), 1)
    key = np.stack([comp, tile[:, 0], tile[:, 1]], axis=1)
    _, inverse, counts = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    inverse = inverse.ravel()
    order = np.argsort(inverse, kind="stable")
    bounds = np.concatenate([[0], np.cumsum(counts)])
    clusters = []
    for g in range(len(counts)):
        if counts[g] < min_cells:
            continue
        clusters.append(FrontierCluster(cells[order[bounds[g] : bounds[g + 1]]]))
    clusters.sort(key=lambda c: (-c.size, tuple(c.cells[0])))
    return clusters


def frontier_clusters(
    known: np.ndarray, occupied: np.ndarray, min_cells: int = 4, max_extent_cells: int = 30
) -> list[FrontierCluster]:
    """Frontier cells of ``known`` clustered into groups (the candidate frontier vertices)."""
    return cluster_frontiers(frontier_cells(known, occupied), min_cells, max_extent_cells)
