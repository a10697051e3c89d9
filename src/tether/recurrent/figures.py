"""Figures of one exploration run: explored area over time, and the map known at the BS."""

from __future__ import annotations

from typing import Any

import numpy as np

from tether.viz.plots import pyplot
from tether.world.grid import OccupancyGrid


def explored_over_time(t_s: np.ndarray, explored: np.ndarray, n_connected: np.ndarray) -> Any:
    """Explored fraction known at the BS and robots connected to it, against time."""
    fig, ax = pyplot().subplots(figsize=(6, 3.5))
    ax.plot(t_s, 100 * explored, label="explored (known at BS)")
    ax2 = ax.twinx()
    ax2.plot(t_s, n_connected, color="tab:orange", lw=0.8, alpha=0.6)
    ax2.set_ylabel("robots connected to BS", color="tab:orange")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("explored area [%]")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    return fig


def known_map(
    grid: OccupancyGrid, known: np.ndarray, trails_m: np.ndarray, base_m: np.ndarray
) -> Any:
    """The map known at the BS at the end, robot trails ``(T, n, 2)`` and the BS, in metres."""
    img = np.full(grid.shape, 0.6)
    img[known & ~grid.occupied] = 1.0
    img[known & grid.occupied] = 0.0
    (x0, y0), (x1, y1) = grid.bounds_m
    fig, ax = pyplot().subplots(figsize=(7, 7 * grid.shape[1] / max(grid.shape[0], 1)))
    ax.imshow(img.T, origin="lower", cmap="gray", vmin=0, vmax=1, interpolation="nearest",
              extent=(x0, x1, y0, y1))  # fmt: skip
    for r in range(trails_m.shape[1]):
        ax.plot(trails_m[:, r, 0], trails_m[:, r, 1], lw=0.7)
    ax.plot(*base_m, "s", color="green", ms=8, label="BS")
    ax.scatter(trails_m[-1, :, 0], trails_m[-1, :, 1], s=12, c="blue", zorder=3)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    fig.tight_layout()
    return fig
