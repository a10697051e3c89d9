"""Communication link models on occupancy grids (registered in ``LINK_MODELS``).

The recurrent-connectivity paper (Banfi et al., Sec. VII) builds the
communication edges ``C^t`` with the conservative limited line-of-sight model:
two locations communicate when they are within 150 cells and the straight
segment between them crosses only free cells of the *known* map (unknown cells
block, so a link predicted on the known map also exists in reality).

A link model is created from the registry by name with its parameters, e.g.
``LINK_MODELS.get("los")(range_cells=150)``, and answers
``model.linked(free, a, b)`` for pairs of points in cell coordinates (see
:mod:`tether.sensing.depth` for the convention) on a boolean ``free`` mask.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from tether.registry import LINK_MODELS
from tether.world.los import segment_free

__all__ = ["DiskLinks", "LinkModel", "LineOfSightLinks", "link_pairs"]


class LinkModel(Protocol):
    range_cells: float

    def linked(self, free: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray: ...


@LINK_MODELS.register("los")
@dataclass
class LineOfSightLinks:
    """Limited line of sight: within ``range_cells`` and a free straight segment."""

    range_cells: float = 150.0

    def linked(self, free: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        a = np.atleast_2d(np.asarray(a, dtype=float))
        b = np.atleast_2d(np.asarray(b, dtype=float))
        close = np.linalg.norm(b - a, axis=1) <= self.range_cells
        out = np.zeros(len(a), dtype=bool)
        if close.any():
            out[close] = segment_free(free, a[close], b[close])
        return out

    def blocked_forever(
        self, known_occupied: np.ndarray, a: np.ndarray, b: np.ndarray
    ) -> np.ndarray:
        """Pairs that no growth of the known map can link: too far or through a known obstacle."""
        a = np.atleast_2d(np.asarray(a, dtype=float))
        b = np.atleast_2d(np.asarray(b, dtype=float))
        far = np.linalg.norm(b - a, axis=1) > self.range_cells
        hit = ~segment_free(~known_occupied, a, b)
        return far | hit


@LINK_MODELS.register("disk")
@dataclass
class DiskLinks:
    """Unit-disk model: within ``range_cells``, obstacles ignored."""

    range_cells: float = 150.0

    def linked(self, free: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        a = np.atleast_2d(np.asarray(a, dtype=float))
        b = np.atleast_2d(np.asarray(b, dtype=float))
        return np.linalg.norm(b - a, axis=1) <= self.range_cells

    def blocked_forever(
        self, known_occupied: np.ndarray, a: np.ndarray, b: np.ndarray
    ) -> np.ndarray:
        """Pairs beyond range (obstacles play no role)."""
        return ~self.linked(known_occupied, a, b)


def link_pairs(model: LinkModel, free: np.ndarray, points: np.ndarray) -> np.ndarray:
    """All linked pairs ``(i, j)``, ``i < j``, among ``points`` (``(k, 2)`` array)."""
    points = np.atleast_2d(np.asarray(points, dtype=float))
    i, j = np.triu_indices(len(points), k=1)
    if len(i) == 0:
        return np.empty((0, 2), dtype=np.intp)
    d = np.linalg.norm(points[i] - points[j], axis=1)
    keep = d <= model.range_cells
    i, j = i[keep], j[keep]
    ok = model.linked(free, points[i], points[j])
    return np.stack([i[ok], j[ok]], axis=1)
