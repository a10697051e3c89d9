"""Static figures of a run in the one look (:mod:`tether.viz.style`).

* :func:`series_over_time`, :func:`links_over_time`: quantities against time (s),
  one line per labelled series, with a title and a legend;
* :func:`snapshot`: the team at a few instants, top view in metres, with the
  world's obstacles (2-D cells; 3-D buildings and walls as footprints shaded by
  height, with a side view under each panel so robots at two heights stay apart),
  links coloured by margin, robots by role / connection to the base station, the
  leader, fixed nodes such as the base station, and a planned path;
* :func:`team_snapshot`: :func:`snapshot` of a recorder at its first, middle and
  last recorded steps (what ``snapshot.png`` of a run folder shows).
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import cache
from types import ModuleType
from typing import TYPE_CHECKING, Any

import numpy as np

from tether.targets_recorded import FINISHED, OPEN, recorded_targets
from tether.viz import style

if TYPE_CHECKING:
    from matplotlib.figure import Figure

#: width of one snapshot panel (inches)
PANEL_IN = 3.6
#: width of the legend column of a snapshot (inches)
LEGEND_IN = 2.1
TIME_LABEL = "time (s)"


@cache
def pyplot() -> ModuleType:
    """``matplotlib.pyplot`` on the Agg backend, imported when the first figure is drawn.

    pyplot (with the artists it loads) is about half a second of a run's start-up; a run
    or a sweep trial with ``figures: false`` never pays it
    (``tests/test_lazy_pyplot.py``).
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def link_range_m(scenario: Any, params: Any = None) -> float | None:
    """The range links are measured against for their margin: the strategy's link range
    (``comm_range_m`` or ``rs_m``), else the scenario's sensing range."""
    raw = scenario.strategy.params if scenario is not None else {}
    for key in ("comm_range_m", "rs_m"):
        value = getattr(params, key, None)
        if value is None:
            value = raw.get(key)
        if isinstance(value, int | float) and not isinstance(value, bool) and value > 0:
            return float(value)
    if scenario is not None:
        return float(scenario.sensing.range_m)
    return None


def series_over_time(
    series: dict[str, tuple[np.ndarray, np.ndarray]],
    xlabel: str,
    ylabel: str,
    reference: tuple[float, str] | None = None,
    *,
    title: str | None = None,
) -> Figure:
    """One line per labelled ``(x, y)`` series, with an optional horizontal reference."""
    fig, ax = pyplot().subplots(figsize=(6.4, 3.6), layout="constrained")
    for label, (x, y) in series.items():
        ax.plot(x, y, label=label, lw=1.3)
    if reference is not None:
        ax.axhline(reference[0], color=style.CURSOR, ls=":", lw=1, label=reference[1])
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.set_ylim(bottom=0)
    ax.grid(alpha=0.3)
    ax.set_facecolor(style.BACKGROUND)
    if title:
        ax.set_title(title, fontsize=10)
    style.place_legend(ax)
    return fig


def links_over_time(
    series: dict[str, tuple[np.ndarray, np.ndarray]], n_nodes: int, *, title: str | None = None
) -> Figure:
    """Number of links against time, one line per labelled series (the paper's Fig. 5), with
    the links of a spanning tree of ``n_nodes`` (robots and fixed nodes) for reference."""
    spanning = (n_nodes - 1, f"spanning tree ({n_nodes - 1} links)")
    fig = series_over_time(
        series, TIME_LABEL, "number of links", spanning, title=title or "links over time"
    )
    fig.axes[0].yaxis.get_major_locator().set_params(integer=True)
    return fig


def _view_box(
    points: np.ndarray, world: Any, range_m: float | None, whole_world: bool
) -> np.ndarray:
    """``(2, 2)`` x-y box: the whole grid for ``whole_world``, else where the team is
    (padded by half a link range where there are obstacles to see, clipped to the grid)."""
    grid = getattr(world, "grid", None)
    if whole_world and grid is not None:
        return np.asarray(grid.bounds_m, dtype=float)[:, :2].copy()
    pts = points[np.all(np.isfinite(points), axis=1)]
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    pad = max(0.08 * float(np.max(hi - lo)), 1.0)
    if grid is not None and range_m:
        pad = max(pad, 0.5 * float(range_m))
    box = np.stack([lo - pad, hi + pad])
    if grid is not None:
        b = np.asarray(grid.bounds_m, dtype=float)[:, :2]
        box = np.stack([np.maximum(box[0], b[0]), np.minimum(box[1], b[1])])
        if np.any(box[1] <= box[0]):  # the team outside its grid: show both
            box = np.stack([np.minimum(lo - pad, b[0]), np.maximum(hi + pad, b[1])])
    return box


def _segments(nodes: np.ndarray, pairs: np.ndarray, axes: list[int]) -> np.ndarray:
    pairs = np.asarray(pairs, dtype=int).reshape(-1, 2)
    pairs = pairs[np.all(pairs < len(nodes), axis=1)]
    if not len(pairs):
        return np.zeros((0, 2, 2))
    return np.stack([nodes[pairs[:, 0]][:, axes], nodes[pairs[:, 1]][:, axes]], axis=1)


def _link_rgba(nodes: np.ndarray, pairs: np.ndarray, range_m: float | None) -> Any:
    pairs = np.asarray(pairs, dtype=int).reshape(-1, 2)
    pairs = pairs[np.all(pairs < len(nodes), axis=1)]
    if range_m is None or not len(pairs):
        return style.LINK_PLAIN
    d = np.linalg.norm(nodes[pairs[:, 0]] - nodes[pairs[:, 1]], axis=1)
    return style.link_colours(style.link_margin(d, range_m))


class _Panel:
    """One instant: its top view (and side view in 3-D) and what is drawn on them."""

    def __init__(self, top: Any, side: Any, world: Any, range_m: float | None) -> None:
        self.top, self.side, self.world, self.range_m = top, side, world, range_m

    def obstacles(self, box: np.ndarray) -> Any:
        grid = getattr(self.world, "grid", None)
        img = style.draw_obstacles_topdown(self.top, grid, colorbar=False)
        bounds = getattr(self.world, "bounds_m", None)
        if grid is None and bounds is not None:  # free space with walls around it
            b = np.asarray(bounds, dtype=float)[:, :2]
            from matplotlib.patches import Rectangle

            self.top.add_patch(
                Rectangle(b[0], *(b[1] - b[0]), fill=False, ec=style.OCCUPIED, lw=1.5, zorder=1)
            )
        if self.side is not None:
            style.draw_obstacles_side(self.side, grid, span_m=(box[0, 1], box[1, 1]), density=True)
        return img

    def team(
        self,
        pos: np.ndarray,
        pairs: np.ndarray,
        fixed: np.ndarray | None,
        colours: np.ndarray,
        leader: int | None,
        z_span: tuple[float, float] | None,
    ) -> None:
        nodes = pos if fixed is None else np.vstack([pos, fixed[:, : pos.shape[1]]])
        rgba = _link_rgba(nodes, pairs, self.range_m)
        views: list[tuple[Any, list[int]]] = [(self.top, [0, 1])]
        if self.side is not None:
            views.append((self.side, [0, 2]))
        from matplotlib.collections import LineCollection

        for ax, axes in views:
            ax.add_collection(
                LineCollection(_segments(nodes, pairs, axes), colors=rgba, lw=1.1, zorder=3)
            )
            order = np.arange(len(pos))
            sizes = np.full(len(pos), 30.0)
            if z_span is not None and axes == [0, 1]:  # higher robots larger and on top
                order = np.argsort(pos[:, 2], kind="stable")
                lo, hi = z_span
                sizes = 22.0 + 34.0 * (pos[:, 2] - lo) / max(hi - lo, 1e-9)
            ax.scatter(
                pos[order][:, axes[0]],
                pos[order][:, axes[1]],
                s=sizes[order],
                c=colours[order],
                edgecolors=style.ROBOT_EDGE,
                linewidths=0.6,
                zorder=4,
            )
            if leader is not None and 0 <= leader < len(pos):
                ax.scatter(
                    [pos[leader, axes[0]]],
                    [pos[leader, axes[1]]],
                    s=80,
                    c=style.LEADER,
                    edgecolors=style.ROBOT_EDGE,
                    linewidths=0.9,
                    zorder=5,
                )
            if fixed is not None and len(fixed):
                f = np.asarray(fixed, dtype=float)
                if f.shape[1] > max(axes):
                    ax.scatter(
                        f[:, axes[0]],
                        f[:, axes[1]],
                        marker="s",
                        s=70,
                        c=style.BASE_STATION,
                        edgecolors=style.ROBOT_EDGE,
                        zorder=5,
                    )

    def targets(self, points: np.ndarray, states: np.ndarray) -> None:
        """Targets as stars: filled while open, hollow once reached or dropped."""
        views = [(self.top, 0, 1)] + ([(self.side, 0, 2)] if self.side is not None else [])
        for ax, a, b in views:
            if b >= points.shape[1]:
                continue
            for state, face in ((OPEN, style.TARGET), (FINISHED, "none")):
                mask = states == state
                if mask.any():
                    ax.scatter(points[mask, a], points[mask, b], marker="*", s=110, c=face,
                               edgecolors=style.ROBOT_EDGE, linewidths=0.7, zorder=5)  # fmt: skip

    def path(self, path: np.ndarray) -> None:
        self.top.plot(path[:, 0], path[:, 1], ls="--", color=style.PATH, lw=1.4, zorder=2)
        if self.side is not None and path.shape[1] > 2:
            self.side.plot(path[:, 0], path[:, 2], ls="--", color=style.PATH, lw=1.2, zorder=2)


def snapshot(
    positions: Sequence[np.ndarray],
    links: Sequence[np.ndarray],
    titles: Sequence[str],
    *,
    path: np.ndarray | None = None,
    leader: int | None = None,
    world: Any = None,
    fixed: np.ndarray | None = None,
    roles: Sequence[np.ndarray] | None = None,
    connected: Sequence[np.ndarray] | None = None,
    range_m: float | None = None,
    title: str | None = None,
    whole_world: bool = False,
    path_label: str = "planned path",
    targets: np.ndarray | None = None,
    target_states: Sequence[np.ndarray] | None = None,
) -> Figure:
    """The team at a few instants (the silent paper's Fig. 4), in the one look.

    ``positions[k]`` are the robots ``(n, dim)`` at instant ``k``; ``links[k]`` pairs of
    node indices, where ``n..`` are the ``fixed`` nodes (e.g. a base station, drawn as a
    square). Robots are coloured by ``roles[k]`` (names), else by ``connected[k]``
    (to the base station), else all alike; ``leader`` is magenta and larger. Links are
    coloured by margin ``1 - d / range_m`` (plain without a range). ``targets`` ``(m, dim)``
    are stars, drawn by ``target_states[k]`` (:mod:`tether.targets_recorded`; default:
    all open). All panels share one view: the whole grid with ``whole_world``, else the
    box around the team, the path and the fixed nodes. 3-D runs get a side view (x
    against height) under each top view, which shows buildings as footprints shaded by
    height.
    """
    k = len(positions)
    dim = int(np.asarray(positions[0]).shape[1])
    fixed = None if fixed is None else np.atleast_2d(np.asarray(fixed, dtype=float))
    three_d = dim == 3
    extra = [np.asarray(path, dtype=float)[:, :2]] if path is not None else []
    if fixed is not None:
        extra.append(np.asarray(fixed, dtype=float)[:, :2])
    if targets is not None:
        targets = np.atleast_2d(np.asarray(targets, dtype=float))
        extra.append(targets[:, :2])
    pts = np.concatenate([np.asarray(p, dtype=float)[:, :2] for p in positions] + extra)
    box = _view_box(pts, world, range_m, whole_world)
    aspect = float((box[1, 1] - box[0, 1]) / max(box[1, 0] - box[0, 0], 1e-9))
    top_h = PANEL_IN * min(max(aspect, 0.45), 1.9)
    side_h = 1.3 if three_d else 0.0
    grid = getattr(world, "grid", None)
    has_obstacles = bool(getattr(world, "has_obstacles", False))
    colorbar = three_d and has_obstacles
    fig = pyplot().figure(
        figsize=(PANEL_IN * k + LEGEND_IN + (0.8 if colorbar else 0.0), top_h + side_h + 1.0),
        layout="constrained",
    )
    gs = fig.add_gridspec(
        2 if three_d else 1, k, height_ratios=[top_h, side_h] if three_d else None
    )
    role_map = None
    if roles is not None:
        role_map = style.role_colour_map([str(r) for rs in roles for r in np.asarray(rs)])
    z_span = None
    if three_d:
        z = np.concatenate([np.asarray(p, dtype=float)[:, 2] for p in positions])
        z_span = (float(np.nanmin(z)), float(np.nanmax(z)))
    img, tops = None, []
    for c in range(k):
        top = fig.add_subplot(gs[0, c])
        side = fig.add_subplot(gs[1, c], sharex=top) if three_d else None
        panel = _Panel(top, side, world, range_m)
        img = panel.obstacles(box) or img
        if path is not None:
            panel.path(np.asarray(path, dtype=float))
        pos = np.asarray(positions[c], dtype=float)
        colours = style.robot_colours(
            len(pos),
            roles=None if roles is None else [str(r) for r in np.asarray(roles[c])],
            role_map=role_map,
            leader=leader,
            connected=None if connected is None else np.asarray(connected[c], dtype=bool),
        )
        panel.team(pos, links[c], fixed, colours, leader, z_span)
        if targets is not None:
            states = np.full(len(targets), OPEN) if target_states is None else target_states[c]
            panel.targets(targets, np.asarray(states))
        style.label_axes(top, title=titles[c])
        if side is not None:
            top.set_anchor("S")  # down onto its side view
        top.set_xlim(box[0, 0], box[1, 0])
        top.set_ylim(box[0, 1], box[1, 1])
        if side is not None:
            side.set_xlabel(style.X_LABEL)
            side.set_ylabel(style.Z_LABEL)
            side.set_facecolor(style.BACKGROUND)
            side.set_title("side view", fontsize=8, loc="left")
            ztop = max(z_span[1], float(grid.bounds_m[1, 2]) if grid is not None else z_span[1])
            side.set_ylim(min(z_span[0], 0.0), ztop + 0.5)
        tops.append((top, side))
    if colorbar and img is not None:
        cb = fig.colorbar(img, ax=[t for t, _ in tops], fraction=0.04, pad=0.01, shrink=0.7)
        cb.set_label("obstacle height (m)")
    any_links = any(len(np.asarray(lk).reshape(-1, 2)) for lk in links)
    if any_links and range_m is not None:
        style.link_margin_colourbar(fig, ax=[t for t, _ in tops], fraction=0.03, pad=0.01,
                                    shrink=0.6)  # fmt: skip
    handles = style.legend_handles(
        roles=role_map,
        leader=leader is not None,
        base_station=fixed is not None and len(fixed) > 0,
        exploration=connected is not None and roles is None,
        path=path is not None,
        targets=targets is not None,
        targets_finished=target_states is not None
        and any(np.any(np.asarray(s) == FINISHED) for s in target_states),
        links=any_links,
        path_label=path_label,
        link_margins=range_m is not None,
        obstacles=None if not has_obstacles else ("3d" if grid.dim == 3 else "2d"),
        boundary=grid is None and getattr(world, "bounds_m", None) is not None,
    )
    fig.legend(handles=handles, loc="outside right upper", fontsize=8, frameon=False)
    if title:
        fig.suptitle(title, fontsize=11)
    if three_d:
        _align_side_views(fig, tops)
    return fig


def _align_side_views(fig: Figure, panels: list[tuple[Any, Any]]) -> None:
    """Give each side view the width of its top view (equal aspect makes the top view
    narrower than its cell), so a robot's x is the same in both; then freeze the layout."""
    fig.get_layout_engine().execute(fig)  # the constrained layout, without drawing
    for top, side in panels:
        top.apply_aspect()
        t, s = top.get_position(), side.get_position()
        side.set_position((t.x0, s.y0, t.width, s.height))
    fig.set_layout_engine("none")


def _per_instant(recording: Any, idx: list[int], key: str) -> list[np.ndarray] | None:
    values = [recording.robot_values[i] if i < len(recording.robot_values) else {} for i in idx]
    if not all(key in v for v in values):
        return None
    return [np.asarray(v[key]) for v in values]


def team_snapshot(
    recording: Any,
    world: Any,
    dt_s: float,
    *,
    range_m: float | None = None,
    leader: int | None = None,
    path: np.ndarray | None = None,
    path_label: str = "planned path",
    title: str | None = None,
) -> Figure | None:
    """:func:`snapshot` of a :class:`tether.record.TrajectoryRecorder` at its first, middle
    and last recorded steps: roles and connection from its robot values, its fixed nodes
    (a base station, and then the whole map is shown), the targets its events record
    (:mod:`tether.targets_recorded`). None without recorded positions."""
    if not recording.positions:
        return None
    n = len(recording.positions)
    idx = sorted({0, n // 2, n - 1})
    fixed = recording.fixed
    dim = int(np.asarray(recording.positions[0]).shape[1])
    marks = recorded_targets(getattr(recording, "events", ()), dim)
    return snapshot(
        [recording.positions[i] for i in idx],
        [recording.links[i] for i in idx],
        [f"t = {recording.position_steps[i] * dt_s:g} s" for i in idx],
        path=path,
        leader=leader,
        world=world,
        fixed=fixed,
        roles=_per_instant(recording, idx, "role"),
        connected=_per_instant(recording, idx, "connected"),
        range_m=range_m,
        title=title,
        whole_world=fixed is not None,
        path_label=path_label,
        targets=None if marks is None else marks.positions_m,
        target_states=None
        if marks is None
        else [
            marks.states(recording.position_steps[i], recording.position_steps[i] * dt_s)
            for i in idx
        ],  # fmt: skip
    )
