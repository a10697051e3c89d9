"""Targets for explorers from a shared map's frontiers (cells).

The exploration layer the continuous-connectivity paper assumes ("targets come from an
exploration layer"): every explorer without a target gets the frontier of best utility
``g(f) / d^2`` on the map it holds, as every explorer of the mission chooses (``g``: the
unknown cells within the sensor range of the frontier, ``d``: the geodesic distance on
the known free space, both in cells). Frontiers already given to another robot (within
``spacing_cells`` of its target) and banned ones (given before and dropped or reached)
are skipped.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tether.paths.geodesic import CoarseGrid
from tether.recurrent.planning.expgraph import frontier_nodes, window_counts

__all__ = ["FrontierChoice", "FrontierPicker"]


@dataclass
class FrontierChoice:
    """One frontier given to a robot: where (cells), its gain and geodesic distance."""

    robot: int
    cell: np.ndarray  # (2,) cell coordinates of the frontier's coarse node centre
    gain: int
    distance_cells: float


@dataclass
class FrontierPicker:
    """Chooses frontiers of a known map for robots (all lengths in cells).

    Parameters
    ----------
    occupied
        The true map ``(nx, ny)`` (read only where known).
    coarse_factor
        Fine cells per coarse cell of the geodesic grid.
    gain_half_width
        Half width of the window counting unknown cells (the sensor range).
    spacing_cells
        Two robots' targets are at least this far apart.
    min_cluster_cells, max_cluster_extent
        Frontier clustering (as the other paradigms of the mission).
    """

    occupied: np.ndarray
    coarse_factor: int
    gain_half_width: int
    spacing_cells: float
    min_cluster_cells: int = 4
    max_cluster_extent: int = 30

    def __post_init__(self) -> None:
        self.banned: list[np.ndarray] = []

    def ban(self, cell: np.ndarray) -> None:
        """Never choose a frontier within one coarse cell of ``cell`` again."""
        self.banned.append(np.array(cell, dtype=float))

    def _allowed(self, cells: np.ndarray, taken: np.ndarray) -> np.ndarray:
        ok = np.ones(len(cells), dtype=bool)
        if len(self.banned):
            d = np.linalg.norm(cells[:, None] - np.asarray(self.banned)[None], axis=-1)
            ok &= d.min(axis=1) > self.coarse_factor
        if len(taken):
            d = np.linalg.norm(cells[:, None] - taken[None], axis=-1)
            ok &= d.min(axis=1) >= self.spacing_cells
        return ok

    def choose(
        self, known: np.ndarray, positions: np.ndarray, robots: list[int], taken: np.ndarray
    ) -> list[FrontierChoice]:
        """Frontiers for ``robots`` (in that order), each apart from ``taken`` and the others.

        Parameters
        ----------
        known
            The map the robots hold ``(nx, ny)``.
        positions
            ``(n, 2)`` robot positions (cells).
        robots
            The robots that need a target.
        taken
            ``(k, 2)`` the targets other robots hold (cells).
        """
        if not robots:
            return []
        coarse = CoarseGrid(known & ~self.occupied, self.coarse_factor)
        if coarse.n_nodes == 0:
            return []
        allowed = np.ones(coarse.n_nodes, dtype=bool)
        nodes = np.asarray(
            [
                nd
                for nd in frontier_nodes(
                    known,
                    self.occupied,
                    coarse,
                    allowed,
                    self.min_cluster_cells,
                    self.max_cluster_extent,
                )  # fmt: skip
                if nd >= 0
            ],
            dtype=np.intp,
        )
        if len(nodes) == 0:
            return []
        nodes = np.unique(nodes)
        cells = coarse.centre(nodes)
        gain = window_counts(~known, cells, self.gain_half_width)
        taken = np.asarray(taken, dtype=float).reshape(-1, 2)
        out: list[FrontierChoice] = []
        for r in robots:
            src = int(coarse.node_at(positions[r][None])[0])
            if src < 0:
                src = int(coarse.nearest_node(positions[r]))
            if src < 0:
                continue
            dist = coarse.distances([src])[0][nodes]
            ok = self._allowed(cells, taken) & np.isfinite(dist) & (gain > 0)
            if not ok.any():
                continue
            util = np.where(ok, gain / np.maximum(dist, 1.0) ** 2, -np.inf)
            k = int(np.argmax(util))
            out.append(FrontierChoice(r, cells[k].copy(), int(gain[k]), float(dist[k])))
            taken = np.vstack([taken, cells[k][None]])
        return out

    def still_frontier(self, known: np.ndarray, cell: np.ndarray) -> bool:
        """Unknown cells remain within two coarse cells of ``cell`` (a frontier is there)."""
        half = 2 * self.coarse_factor + 1
        return bool(window_counts(~known, np.asarray(cell, float)[None], half)[0] > 0)
