"""Figures of one exploration run, in the one look (:mod:`tether.viz.style`): explored
area over time, and the map known at the base station (BS) at the end of the run."""

from __future__ import annotations

from typing import Any

import numpy as np

from tether.viz import style
from tether.viz.plots import TIME_LABEL, pyplot
from tether.world.grid import OccupancyGrid


def explored_over_time(
    t_s: np.ndarray,
    explored: np.ndarray,
    n_connected: np.ndarray,
    *,
    n_robots: int | None = None,
    title: str = "explored area known at the base station",
) -> Any:
    """Explored area known at the BS (%) and robots connected to it, against time (s)."""
    fig, ax = pyplot().subplots(figsize=(6.4, 3.6), layout="constrained")
    ax.set_facecolor(style.BACKGROUND)
    (explored_line,) = ax.plot(
        t_s,
        100 * np.asarray(explored, dtype=float),
        color=style.CONNECTED,
        lw=1.6,
        label="explored area known at the BS",
    )
    ax2 = ax.twinx()
    (conn_line,) = ax2.step(
        t_s,
        n_connected,
        where="post",
        color=style.BASE_STATION,
        lw=0.8,
        alpha=0.7,
        label="robots connected to the BS",
    )
    top = n_robots if n_robots is not None else int(np.max(n_connected, initial=0))
    ax2.set_ylim(0, max(top, 1) + 0.5)
    ax2.yaxis.get_major_locator().set_params(integer=True)
    ax2.set_ylabel("robots connected to the BS", color=style.BASE_STATION)
    ax.set_xlabel(TIME_LABEL)
    ax.set_ylabel("explored area (%)")
    ax.set_ylim(0, 100)
    ax.grid(alpha=0.3)
    ax.set_title(title, fontsize=10)
    fig.legend(
        handles=[explored_line, conn_line],
        loc="outside lower center",
        ncols=2,
        fontsize=8,
        frameon=False,
    )
    return fig


def known_map(
    grid: OccupancyGrid,
    known: np.ndarray,
    trails_m: np.ndarray,
    base_m: np.ndarray,
    *,
    connected: np.ndarray | None = None,
    title: str = "map known at the base station",
) -> Any:
    """The map known at the BS at the end, robot trails ``(T, n, 2)`` and the BS, in metres.

    Cells are free (known), occupied (known), unknown, or unknown but occupied in the
    true map (a darker grey: a trail through unmapped space never seems to cross a
    wall); the robots at the end are coloured by ``connected`` (to the BS).
    """
    (x0, y0), (x1, y1) = np.asarray(grid.bounds_m, dtype=float)[:, :2]
    aspect = (y1 - y0) / max(x1 - x0, 1e-9)
    aspect = max(aspect, 1e-9)  # the map at its own aspect, at most 9 in wide and 10 in tall
    w_in = min(max(5.5, 4.0 / aspect), 9.0, 10.0 / aspect)
    h_in = w_in * aspect
    left, bottom, right, top = 0.8, 0.6, 2.8, 0.5  # margins (in): labels, legend, title
    fig = pyplot().figure(figsize=(left + w_in + right, bottom + h_in + top))
    fw, fh = fig.get_size_inches()
    ax = fig.add_axes((left / fw, bottom / fh, w_in / fw, h_in / fh))
    style.draw_obstacles_topdown(ax, grid, known=known)
    trails = np.asarray(trails_m, dtype=float)[:, :, :2]
    from matplotlib.collections import LineCollection  # loaded with pyplot already

    ax.add_collection(
        LineCollection(
            list(trails.transpose(1, 0, 2)), colors=style.TRAIL, lw=0.8, alpha=0.6, zorder=2
        )
    )
    end = trails[-1]
    colours = style.robot_colours(
        len(end), connected=None if connected is None else np.asarray(connected, dtype=bool)
    )
    ax.scatter(
        end[:, 0], end[:, 1], s=30, c=colours, edgecolors=style.ROBOT_EDGE, linewidths=0.6, zorder=4
    )
    base = np.asarray(base_m, dtype=float).ravel()
    ax.scatter(
        [base[0]],
        [base[1]],
        marker="s",
        s=80,
        c=style.BASE_STATION,
        edgecolors=style.ROBOT_EDGE,
        zorder=5,
    )
    style.label_axes(ax, title=title)
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    handles = style.legend_handles(
        exploration=connected is not None,
        base_station=True,
        links=False,
        trail=True,
        map_classes=True,
    )
    ax.legend(
        handles=handles,
        loc="upper left",
        bbox_to_anchor=(1.02, 1.0),
        fontsize=8,
        frameon=False,
        borderaxespad=0.0,
    )
    return fig
