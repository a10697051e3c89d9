"""Communication link models on occupancy grids (registered in ``LINK_MODELS``).

The recurrent-connectivity paper (Banfi et al., Sec. VII) builds the
communication edges ``C^t`` with the conservative limited line-of-sight model:
two locations communicate when they are within 150 cells and the straight
segment between them crosses only free cells of the *known* map (unknown cells
block, so a link predicted on the known map also exists in reality).

A link model is created from the registry by name with its parameters, e.g.
``LINK_MODELS.get("los")(range_cells=150)``, and answers
``model.linked(free, a, b)`` for pairs of points in cell coordinates (see
:mod:`tether.recurrent.sensor` for the convention) on a boolean ``free`` mask.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from tether.registry import LINK_MODELS

__all__ = ["DiskLinks", "LinkModel", "LineOfSightLinks", "link_pairs", "segment_free"]


class LinkModel(Protocol):
    range_cells: float

    def linked(self, free: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray: ...


def segment_free(
    free: np.ndarray, a: np.ndarray, b: np.ndarray, step_cells: float = 0.5, chunk: int = 4096
) -> np.ndarray:
    """Boolean ``(k,)``: every half-cell sample of segment ``a[k] -> b[k]`` lies in ``free``.

    Points outside the grid count as blocked.
    """
    a = np.atleast_2d(np.asarray(a, dtype=float))
    b = np.atleast_2d(np.asarray(b, dtype=float))
    out = np.zeros(len(a), dtype=bool)
    if len(a) == 0:
        return out
    nx_, ny_ = free.shape
    length = np.linalg.norm(b - a, axis=1)
    n_samples = int(np.ceil(length.max() / step_cells)) + 1 if len(a) else 2
    s = np.linspace(0.0, 1.0, max(n_samples, 2))
    for lo in range(0, len(a), chunk):
        aa, bb = a[lo : lo + chunk], b[lo : lo + chunk]
        px = aa[:, 0, None] + s * (bb[:, 0] - aa[:, 0])[:, None]
        py = aa[:, 1, None] + s * (bb[:, 1] - aa[:, 1])[:, None]
        ix = np.floor(px).astype(np.intp)
        iy = np.floor(py).astype(np.intp)
        inside = (ix >= 0) & (ix < nx_) & (iy >= 0) & (iy < ny_)
        ok = free[np.clip(ix, 0, nx_ - 1), np.clip(iy, 0, ny_ - 1)] & inside
        out[lo : lo + chunk] = ok.all(axis=1)
    return out


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


@LINK_MODELS.register("disk")
@dataclass
class DiskLinks:
    """Unit-disk model: within ``range_cells``, obstacles ignored."""

    range_cells: float = 150.0

    def linked(self, free: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        a = np.atleast_2d(np.asarray(a, dtype=float))
        b = np.atleast_2d(np.asarray(b, dtype=float))
        return np.linalg.norm(b - a, axis=1) <= self.range_cells


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
