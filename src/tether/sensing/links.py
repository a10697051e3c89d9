"""Communication link models on occupancy grids (registered in ``LINK_MODELS``).

The recurrent-connectivity paper (Banfi et al., Sec. VII) builds the
communication edges ``C^t`` with the conservative limited line-of-sight model:
two locations communicate when they are within 150 cells and the straight
segment between them crosses only free cells of the *known* map (unknown cells
block, so a link predicted on the known map also exists in reality).

A third model, ``signal``, is the kind MRESim uses (its ``PropModel1``): a
log-distance path loss with an attenuation per wall cell crossed and a receive
threshold. Evaluated on a known map with unknown cells counted as walls it is
conservative in the same way: learning the map can only remove walls.

A link model is created from the registry by name with its parameters, e.g.
``LINK_MODELS.get("los")(range_cells=150)``, and answers
``model.linked(free, a, b)`` for pairs of points in cell coordinates (see
:mod:`tether.sensing.depth` for the convention) on a boolean ``free`` mask.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from tether.registry import LINK_MODELS
from tether.world.los import cells_crossed, segment_free

__all__ = ["DiskLinks", "LinkModel", "LineOfSightLinks", "SignalLinks", "link_pairs"]


class LinkModel(Protocol):
    range_cells: float

    def linked(self, free: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray: ...


def _within_range_and(
    range_cells: float,
    a: np.ndarray,
    b: np.ndarray,
    test: Callable[[np.ndarray, np.ndarray], np.ndarray],
) -> np.ndarray:
    """Pairs ``a[k]``-``b[k]`` within ``range_cells`` passing ``test`` (run on those only)."""
    a = np.atleast_2d(np.asarray(a, dtype=float))
    b = np.atleast_2d(np.asarray(b, dtype=float))
    close = np.linalg.norm(b - a, axis=1) <= range_cells
    out = np.zeros(len(a), dtype=bool)
    if close.any():
        out[close] = test(a[close], b[close])
    return out


@LINK_MODELS.register("los")
@dataclass
class LineOfSightLinks:
    """Limited line of sight: within ``range_cells`` and a free straight segment."""

    range_cells: float = 150.0

    def linked(self, free: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return _within_range_and(self.range_cells, a, b, lambda p, q: segment_free(free, p, q))

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


@LINK_MODELS.register("signal")
@dataclass
class SignalLinks:
    """Log-distance path loss with wall attenuation and a receive threshold.

    Received power (dBm) between two points ``d`` cells apart whose segment
    passes through ``w`` non-free cells (walls; :func:`tether.world.los.cells_crossed`)::

        P(d, w) = ref_power_dbm - 10 * exponent * log10(max(d, ref_distance_cells)
                                                        / ref_distance_cells)
                  - wall_loss_db * w

    and the two are linked when ``P >= cutoff_dbm``. Within the reference
    distance the power is ``ref_power_dbm`` (no gain from coming closer). The
    defaults (-40 dBm at 10 cells = 1 m at 0.1 m per cell, exponent 2.5 as in
    MRESim, 3 dB per 0.1 m wall cell, cutoff -70 dBm) give a free-space range of
    158 cells, close to the paper's 150-cell line of sight. ``range_cells`` is
    that free-space range: no pair farther apart can link.
    """

    ref_power_dbm: float = -40.0
    ref_distance_cells: float = 10.0
    exponent: float = 2.5
    wall_loss_db: float = 3.0
    cutoff_dbm: float = -70.0

    def __post_init__(self) -> None:
        if self.ref_distance_cells <= 0 or self.exponent <= 0 or self.wall_loss_db < 0:
            raise ValueError(
                "signal link model: ref_distance_cells and exponent must be > 0, wall_loss_db >= 0"
            )

    @property
    def range_cells(self) -> float:
        if self.ref_power_dbm < self.cutoff_dbm:
            return 0.0
        margin = (self.ref_power_dbm - self.cutoff_dbm) / (10.0 * self.exponent)
        return float(self.ref_distance_cells * 10.0**margin)

    def power_dbm(self, free: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Received power of every pair on the mask ``free`` (other cells are walls)."""
        a = np.atleast_2d(np.asarray(a, dtype=float))
        b = np.atleast_2d(np.asarray(b, dtype=float))
        d = np.maximum(np.linalg.norm(b - a, axis=1), self.ref_distance_cells)
        loss = 10.0 * self.exponent * np.log10(d / self.ref_distance_cells)
        walls = cells_crossed(~np.asarray(free, dtype=bool), a, b)
        return self.ref_power_dbm - loss - self.wall_loss_db * walls

    def linked(self, free: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return _within_range_and(
            self.range_cells, a, b, lambda p, q: self.power_dbm(free, p, q) >= self.cutoff_dbm
        )

    def blocked_forever(
        self, known_occupied: np.ndarray, a: np.ndarray, b: np.ndarray
    ) -> np.ndarray:
        """Pairs that the known obstacles alone already attenuate below the cutoff."""
        return ~self.linked(~np.asarray(known_occupied, dtype=bool), a, b)


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
