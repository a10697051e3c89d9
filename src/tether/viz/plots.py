"""Static figures of a run: links over time and snapshots of the team.

Matplotlib is imported on the first figure drawn, not with this module: importing
it costs about a second, and every run imports this module (through the runner
and the strategies' ``figures`` hooks) while a run without figures draws none.
"""

from __future__ import annotations

import functools
from types import ModuleType
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from matplotlib.figure import Figure


@functools.cache
def pyplot() -> ModuleType:
    """``matplotlib.pyplot`` on the non-interactive Agg backend, imported on first use."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def series_over_time(
    series: dict[str, tuple[np.ndarray, np.ndarray]],
    xlabel: str,
    ylabel: str,
    reference: tuple[float, str] | None = None,
) -> Figure:
    """One line per labelled ``(x, y)`` series, with an optional horizontal reference."""
    fig, ax = pyplot().subplots(figsize=(6.4, 3.6))
    for label, (x, y) in series.items():
        ax.plot(x, y, label=label)
    if reference is not None:
        ax.axhline(reference[0], color="grey", ls=":", lw=1, label=reference[1])
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    return fig


def links_over_time(series: dict[str, tuple[np.ndarray, np.ndarray]], n_robots: int) -> Figure:
    """Number of links against time, one line per labelled series (the paper's Fig. 5)."""
    spanning = (n_robots - 1, f"spanning tree ({n_robots - 1})")
    return series_over_time(series, "time (s)", "number of links", spanning)


def snapshot(
    positions: list[np.ndarray],
    links: list[np.ndarray],
    titles: list[str],
    *,
    path: np.ndarray | None = None,
    leader: int | None = None,
    world: Any = None,
) -> Figure:
    """Team positions with their links at a few instants (the paper's Fig. 4)."""
    k = len(positions)
    fig, axes = pyplot().subplots(1, k, figsize=(4.0 * k, 4.0), squeeze=False)
    all_pts = np.concatenate(positions + ([path] if path is not None else []))
    lo, hi = all_pts[:, :2].min(axis=0), all_pts[:, :2].max(axis=0)
    pad = 0.05 * max(float(np.max(hi - lo)), 1.0)
    for ax, pos, lk, title in zip(axes[0], positions, links, titles, strict=True):
        if world is not None and world.grid is not None and world.dim == 2:
            g = world.grid
            ext = [g.bounds_m[0, 0], g.bounds_m[1, 0], g.bounds_m[0, 1], g.bounds_m[1, 1]]
            ax.imshow(g.occupied.T, origin="lower", extent=ext, cmap="Greys", alpha=0.6)
        if len(lk):
            seg = np.stack([pos[lk[:, 0], :2], pos[lk[:, 1], :2]], axis=1)
            for s in seg:
                ax.plot(s[:, 0], s[:, 1], color="tab:blue", lw=0.6, alpha=0.6)
        ax.scatter(pos[:, 0], pos[:, 1], s=14, color="black", zorder=3)
        if leader is not None:
            ax.scatter(*pos[leader, :2], s=40, color="tab:red", zorder=4, label="leader")
        if path is not None:
            ax.plot(path[:, 0], path[:, 1], color="tab:red", lw=1.0, alpha=0.7)
        ax.set_title(title, fontsize=9)
        ax.set_aspect("equal")
        ax.set_xlim(lo[0] - pad, hi[0] + pad)
        ax.set_ylim(lo[1] - pad, hi[1] + pad)
    fig.tight_layout()
    return fig
