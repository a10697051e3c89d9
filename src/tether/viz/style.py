"""One look for every figure, animation and replay of tether.

Colours are given once here and used by matplotlib (:mod:`tether.viewing.animate`,
figures), by the browser replay (:func:`palette` is embedded in the page) and by
the ROS 2 export (marker colours), so a leader, a base station or a link about
to break looks the same everywhere:

* robots: one colour per ``role`` when the run records roles, the leader magenta,
  exploration robots blue when connected to the base station and orange when not;
* the base station: a purple square;
* links: green (well connected, margin 1) through amber to red (about to break,
  margin 0), where the margin is ``1 - d / range`` or the recorded weight;
* space: free white, occupied near-black, unknown light grey (with the true
  obstacles in a darker grey underneath, so nothing seems to cross a wall);
* 3-D obstacles seen from above: footprints shaded by height (darker is taller).

Axes are always in metres and labelled.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.colors import Colormap

    from tether.world.grid import OccupancyGrid

ROBOT = "#1f77b4"
LEADER = "#e7298a"  # magenta: red is taken by links about to break
BASE_STATION = "#542788"
TARGET = "#ff7f0e"
PATH = "#8c6bb1"
CURSOR = "#222222"
CONNECTED = "#1f77b4"
DISCONNECTED = "#ff7f0e"
ROBOT_EDGE = "#1a1a1a"
TRAIL = "#555555"
LINK_PLAIN = "#7f93a8"  # a link where no range is known to measure its margin by

FREE = "#ffffff"
OCCUPIED = "#2e2e2e"
UNKNOWN = "#d4d4d4"
UNKNOWN_OCCUPIED = "#9c9c9c"
BACKGROUND = "#f7f7f7"

LINK_BAD = "#d62728"
LINK_MID = "#ffbf00"
LINK_GOOD = "#2ca02c"

#: Roles get these colours in order of first appearance (sorted by name for stability);
#: a role called ``leader`` is always :data:`LEADER`. None is red, green or amber (links).
ROLE_CYCLE = (
    "#1f77b4",
    "#9467bd",
    "#17becf",
    "#8c564b",
    "#7f7f7f",
    "#08306b",
    "#c2a5cf",
    "#a6761d",
)

#: Obstacle height seen from above: light (low) to dark (tall) grey-blue.
HEIGHT_STOPS = ("#b9c3cf", "#5b6b7f", "#1c2633")


def _link_cmap() -> Colormap:
    """Link colour by margin in [0, 1]: red (about to break) -> amber -> green."""
    from matplotlib.colors import LinearSegmentedColormap

    return LinearSegmentedColormap.from_list("tether_link", [LINK_BAD, LINK_MID, LINK_GOOD])


def _height_cmap() -> Colormap:
    """Obstacle height seen from above: :data:`HEIGHT_STOPS`, light (low) to dark (tall)."""
    from matplotlib.colors import LinearSegmentedColormap

    return LinearSegmentedColormap.from_list("tether_height", list(HEIGHT_STOPS))


def _map_cmap() -> Colormap:
    """Cell states of a map: 0 free, 1 occupied, 2 unknown free, 3 unknown occupied."""
    from matplotlib.colors import ListedColormap

    return ListedColormap([FREE, OCCUPIED, UNKNOWN, UNKNOWN_OCCUPIED], name="tether_map")


#: the colour maps ``LINK_CMAP``, ``HEIGHT_CMAP`` and ``MAP_CMAP``, made on first use
#: (:func:`__getattr__`): a run without figures never imports matplotlib
_COLORMAPS = {"LINK_CMAP": _link_cmap, "HEIGHT_CMAP": _height_cmap, "MAP_CMAP": _map_cmap}


def __getattr__(name: str) -> Colormap:
    """``style.LINK_CMAP`` (link margins), ``HEIGHT_CMAP`` (obstacle heights) and
    ``MAP_CMAP`` (map cell states), made (and kept) when first asked for."""
    make = _COLORMAPS.get(name)
    if make is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    cmap = globals()[name] = make()
    return cmap


def colormap(name: str) -> Colormap:
    """One of the colour maps of :data:`_COLORMAPS` by its name, e.g. ``"LINK_CMAP"``."""
    return globals()[name] if name in globals() else __getattr__(name)


def to_rgba(colour: Any, alpha: float | None = None) -> tuple[float, float, float, float]:
    """matplotlib's ``to_rgba`` (matplotlib imported on first use)."""
    from matplotlib.colors import to_rgba as rgba

    return rgba(colour, alpha)


X_LABEL = "x (m)"
Y_LABEL = "y (m)"
Z_LABEL = "z (m)"


def link_margin(distance_m: np.ndarray, range_m: float) -> np.ndarray:
    """``1 - d / range`` clipped to [0, 1]: 1 for touching robots, 0 at the range."""
    return np.clip(1.0 - np.asarray(distance_m, dtype=float) / float(range_m), 0.0, 1.0)


def link_colours(margin: np.ndarray) -> np.ndarray:
    """RGBA ``(k, 4)`` for link margins in [0, 1] (see :data:`LINK_CMAP`)."""
    return colormap("LINK_CMAP")(np.clip(np.asarray(margin, dtype=float), 0.0, 1.0))


def link_margin_colourbar(fig: Any, **where: Any) -> Any:
    """A colour bar of link margin on ``fig`` (``where``: ``ax=``, ``cax=``, ...): red at
    0 (a link at the range, about to break) through amber to green at 1 (robots close)."""
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import Normalize

    mappable = ScalarMappable(norm=Normalize(0.0, 1.0), cmap=colormap("LINK_CMAP"))
    bar = fig.colorbar(mappable, **where)
    bar.set_label("link margin, 1 - d / range", fontsize=8)
    bar.set_ticks([0.0, 0.5, 1.0])
    bar.ax.tick_params(labelsize=7)
    return bar


def role_colour_map(roles: Sequence[str]) -> dict[str, str]:
    """A fixed colour for each role name (``leader`` magenta, others from :data:`ROLE_CYCLE`)."""
    out: dict[str, str] = {}
    k = 0
    for role in sorted(set(roles)):
        if role.lower() == "leader":
            out[role] = LEADER
        else:
            out[role] = ROLE_CYCLE[k % len(ROLE_CYCLE)]
            k += 1
    return out


def robot_colours(
    n_robots: int,
    *,
    roles: Sequence[str] | None = None,
    role_map: dict[str, str] | None = None,
    leader: int | None = None,
    connected: np.ndarray | None = None,
) -> np.ndarray:
    """RGBA ``(n, 4)`` of the robots at one instant.

    Priority: ``roles`` (with ``role_map``), else ``connected`` (exploration: to the
    base station or not), else all :data:`ROBOT`; the ``leader`` is magenta on top.
    """
    cols = np.tile(to_rgba(ROBOT), (n_robots, 1))
    if roles is not None:
        role_map = role_map or role_colour_map(roles)
        cols = np.array([to_rgba(role_map.get(str(r), ROBOT)) for r in roles]).reshape(-1, 4)
    elif connected is not None:
        conn = np.asarray(connected, dtype=bool)
        cols[conn] = to_rgba(CONNECTED)
        cols[~conn] = to_rgba(DISCONNECTED)
    if leader is not None and 0 <= leader < n_robots:
        cols[leader] = to_rgba(LEADER)
    return cols


def label_axes(ax: Axes, *, vertical: bool = False, title: str | None = None) -> None:
    """Metre labels on both axes (``vertical``: x and z, a side view), equal aspect."""
    ax.set_xlabel(X_LABEL)
    ax.set_ylabel(Z_LABEL if vertical else Y_LABEL)
    ax.set_aspect("equal")
    ax.set_facecolor(BACKGROUND)
    if title:
        ax.set_title(title, fontsize=10)


def height_map(grid: OccupancyGrid) -> tuple[np.ndarray, np.ndarray]:
    """Top of the highest occupied cell of each column (m above the grid origin; 0 if none),
    and whether the column's lowest cell is free (a door or an overhang: passable below)."""
    occ = grid.occupied
    if occ.ndim == 2:
        return occ.astype(float) * grid.resolution_m, ~occ
    nz = occ.shape[2]
    any_occ = occ.any(axis=2)
    top = nz - np.argmax(occ[:, :, ::-1], axis=2)  # index of the top occupied cell + 1
    heights = np.where(any_occ, top * grid.resolution_m, 0.0)
    return heights, ~occ[:, :, 0]


def map_states(grid: OccupancyGrid, known: np.ndarray | None = None) -> np.ndarray:
    """Cell states for :data:`MAP_CMAP` of a 2-D grid: 0 free, 1 occupied, 2/3 unknown."""
    occ = grid.occupied if grid.occupied.ndim == 2 else grid.occupied.any(axis=2)
    states = occ.astype(np.uint8)
    if known is not None:
        states = np.where(known, states, states + 2).astype(np.uint8)
    return states


def _listed(colour: str) -> Colormap:
    """A one-colour map (for a mask shown in one colour)."""
    from matplotlib.colors import ListedColormap

    return ListedColormap([colour])


def _extent(grid: OccupancyGrid) -> list[float]:
    b = grid.bounds_m
    return [float(b[0, 0]), float(b[1, 0]), float(b[0, 1]), float(b[1, 1])]


def draw_obstacles_topdown(
    ax: Axes,
    grid: OccupancyGrid | None,
    *,
    known: np.ndarray | None = None,
    colorbar: bool = True,
) -> Any:
    """Draw a world's obstacles seen from above; returns the image artist (or None).

    2-D grids show free / occupied and, with ``known`` (boolean per cell), unknown space;
    3-D grids show building and wall footprints shaded by height (a colour bar in
    metres), doors and overhangs (free at the ground) hatched lighter.
    """
    if grid is None:
        return None
    if grid.dim == 2:
        states = map_states(grid, known)
        return ax.imshow(
            states.T,
            origin="lower",
            extent=_extent(grid),
            cmap=colormap("MAP_CMAP"),
            vmin=-0.5,
            vmax=3.5,
            interpolation="nearest",
            zorder=0,
        )
    heights, ground_free = height_map(grid)
    shown = np.ma.masked_where(heights <= 0, heights)
    top = float(grid.bounds_m[1, 2] - grid.bounds_m[0, 2])
    img = ax.imshow(
        shown.T,
        origin="lower",
        extent=_extent(grid),
        cmap=colormap("HEIGHT_CMAP"),
        vmin=0.0,
        vmax=max(top, 1e-9),
        interpolation="nearest",
        zorder=0,
    )
    passable = np.ma.masked_where(~(ground_free & (heights > 0)), np.ones_like(heights))
    ax.imshow(
        passable.T,
        origin="lower",
        extent=_extent(grid),
        cmap=_listed(FREE),
        alpha=0.6,
        interpolation="nearest",
        zorder=0.5,
    )
    if colorbar:
        cb = ax.figure.colorbar(img, ax=ax, fraction=0.035, pad=0.02)
        cb.set_label("obstacle height (m)")
    return img


def draw_obstacles_side(
    ax: Axes,
    grid: OccupancyGrid | None,
    *,
    axis: int = 1,
    span_m: tuple[float, float] | None = None,
    density: bool = False,
) -> Any:
    """Side view (x horizontal, z vertical) of a 3-D grid: occupied anywhere along ``axis``
    (only within ``span_m`` along that axis, e.g. the y range of the top view).

    With ``density`` a cell of the view is the darker the more of the span behind it is
    occupied (a wall seen edge-on is solid, rooms' cross walls stay faint), so a view
    through a whole office is not one grey block."""
    if grid is None or grid.dim != 3:
        return None
    occ = grid.occupied
    if span_m is not None:
        lo = int(np.floor((span_m[0] - grid.origin_m[axis]) / grid.resolution_m))
        hi = int(np.ceil((span_m[1] - grid.origin_m[axis]) / grid.resolution_m))
        lo, hi = max(lo, 0), min(max(hi, lo + 1), occ.shape[axis])
        occ = np.take(occ, np.arange(lo, hi), axis=axis) if hi > lo else occ[:0]
    depth = occ.shape[axis]
    frac = occ.mean(axis=axis) if depth else np.zeros(np.delete(grid.shape, axis))
    b = grid.bounds_m
    keep = [0, 1, 2]
    keep.remove(axis)
    ext = [float(b[0, keep[0]]), float(b[1, keep[0]]), float(b[0, 2]), float(b[1, 2])]
    if density:
        rgba = np.zeros((*frac.T.shape, 4))
        rgba[..., :3] = to_rgba(UNKNOWN_OCCUPIED)[:3]
        rgba[..., 3] = np.where(frac.T > 0, 0.2 + 0.8 * frac.T, 0.0)
        return ax.imshow(
            rgba, origin="lower", extent=ext, interpolation="nearest", aspect="auto", zorder=0
        )
    shown = np.ma.masked_where(frac <= 0, np.ones(frac.shape))
    return ax.imshow(
        shown.T,
        origin="lower",
        extent=ext,
        cmap=_listed(UNKNOWN_OCCUPIED),
        interpolation="nearest",
        aspect="auto",
        zorder=0,
    )


def legend_handles(
    *,
    roles: dict[str, str] | None = None,
    leader: bool = False,
    base_station: bool = False,
    exploration: bool = False,
    targets: bool = False,
    targets_finished: bool = False,
    path: bool = False,
    links: bool = True,
    unknown: bool = False,
    path_label: str = "planned path",
    link_margins: bool = True,
    obstacles: str | None = None,
    map_classes: bool = False,
    trail: bool = False,
    boundary: bool = False,
    robots: bool = True,
) -> list[Any]:
    """Legend entries for what a picture shows, in the one look.

    ``obstacles`` is ``"2d"`` (occupied cells) or ``"3d"`` (footprints shaded by
    height); ``map_classes`` lists the four cell states of a known map (free, occupied,
    unknown, unknown but occupied in the true map); ``link_margins=False`` gives one
    plain link entry (no range known to colour links by).
    """
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    def dot(colour: str, label: str, marker: str = "o", size: float = 7) -> Line2D:
        return Line2D(
            [], [], ls="", marker=marker, ms=size, mfc=colour, mec=ROBOT_EDGE, label=label
        )

    out: list[Any] = []
    if roles:
        out += [dot(c, f"robot: {r}") for r, c in roles.items()]
    elif exploration:
        out += [dot(CONNECTED, "robot, connected to BS"), dot(DISCONNECTED, "robot, out of comm")]
    elif robots:
        out.append(dot(ROBOT, "robot"))
    if leader:
        out.append(dot(LEADER, "leader", size=9))
    if base_station:
        out.append(dot(BASE_STATION, "base station", marker="s", size=9))
    if targets:
        out.append(dot(TARGET, "target", marker="*", size=11))
    if targets_finished:
        out.append(dot("none", "target, reached or dropped", marker="*", size=11))
    if path:
        out.append(Line2D([], [], color=PATH, lw=1.5, ls="--", label=path_label))
    if trail:
        out.append(Line2D([], [], color=TRAIL, lw=1.0, alpha=0.6, label="robot trail"))
    if links and link_margins:
        out.append(Line2D([], [], color=LINK_GOOD, lw=2, label="link, strong"))
        out.append(Line2D([], [], color=LINK_BAD, lw=2, label="link, near range"))
    elif links:
        out.append(Line2D([], [], color=LINK_PLAIN, lw=2, label="link"))
    if unknown:
        out.append(Patch(fc=UNKNOWN, ec="#888888", label="unknown"))
        out.append(Patch(fc=OCCUPIED, label="occupied (known)"))
    if map_classes:
        out.append(Patch(fc=FREE, ec="#888888", label="free (known)"))
        out.append(Patch(fc=OCCUPIED, label="occupied (known)"))
        out.append(Patch(fc=UNKNOWN, ec="#888888", label="unknown"))
        out.append(Patch(fc=UNKNOWN_OCCUPIED, label="unknown, obstacle in true map"))
    if obstacles == "2d":
        out.append(Patch(fc=OCCUPIED, label="obstacle / wall"))
    elif obstacles == "3d":
        out.append(Patch(fc=HEIGHT_STOPS[1], label="building / wall (darker: taller)"))
    if boundary:
        out.append(Patch(fc="none", ec=OCCUPIED, lw=1.5, label="world boundary"))
    return out


#: a legend with more entries than this, or a longer label, goes beside the plot
LEGEND_INSIDE_ENTRIES = 4
LEGEND_INSIDE_CHARS = 24


def place_legend(ax: Any) -> Any:
    """The legend of ``ax``: inside where it is small, else beside the plot (the figure,
    in constrained layout, is widened for it), so it never covers the data."""
    handles, labels = ax.get_legend_handles_labels()
    if not labels:
        return None
    longest = max(len(label) for label in labels)
    if len(labels) <= LEGEND_INSIDE_ENTRIES and longest <= LEGEND_INSIDE_CHARS:
        return ax.legend(fontsize=8)
    fig = ax.figure
    width, height = fig.get_size_inches()
    fig.set_size_inches(width + 0.4 + 0.062 * longest, height)
    return fig.legend(handles, labels, loc="outside right upper", fontsize=7, frameon=False)


def palette() -> dict[str, Any]:
    """The colours above for the browser replay (hex strings and link colour stops)."""
    return {
        "robot": ROBOT,
        "leader": LEADER,
        "base_station": BASE_STATION,
        "target": TARGET,
        "path": PATH,
        "cursor": CURSOR,
        "connected": CONNECTED,
        "disconnected": DISCONNECTED,
        "free": FREE,
        "occupied": OCCUPIED,
        "unknown": UNKNOWN,
        "unknown_occupied": UNKNOWN_OCCUPIED,
        "background": BACKGROUND,
        "link_stops": [LINK_BAD, LINK_MID, LINK_GOOD],
        "height_stops": list(HEIGHT_STOPS),
        "role_cycle": list(ROLE_CYCLE),
    }


def rgba_floats(colour: str, alpha: float = 1.0) -> tuple[float, float, float, float]:
    """``(r, g, b, a)`` in [0, 1] of a colour (for ROS markers)."""
    r, g, b, _ = to_rgba(colour)
    return (r, g, b, alpha)
