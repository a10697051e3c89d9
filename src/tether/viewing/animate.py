"""``tether animate``: a GIF (Pillow) or MP4 (ffmpeg) of a run, in the one look.

Top view in metres with obstacles (3-D buildings and walls as footprints shaded
by height), links coloured by margin, robots by role / leader / connection to the
base station, planned path, targets, the base station and, for exploration, the
map the robots have seen; 3-D runs get a side view (x against height) under the
top view so robots stacked at two heights stay apart; a strip below follows the
run's link count (or explored fraction) with a cursor.
"""

from __future__ import annotations

import shutil
import subprocess
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402
from PIL import Image  # noqa: E402

from tether.errors import TetherError  # noqa: E402
from tether.progress import progress_bar  # noqa: E402
from tether.targets_recorded import FINISHED, HIDDEN  # noqa: E402
from tether.viewing.known import first_seen  # noqa: E402
from tether.viewing.output import check_target, write_output  # noqa: E402
from tether.viewing.runfolder import RunData, frame_indices, load_run  # noqa: E402
from tether.viz import style  # noqa: E402

DEFAULT_FPS = 10.0
DEFAULT_DURATION_S = 20.0
TRAIL_FRAMES = 8


@dataclass
class Animation:
    path: Path
    format: str
    n_frames: int
    size_px: tuple[int, int]
    bytes: int
    seconds: float


def _view_box(run: RunData) -> np.ndarray:
    """``(2, 2)`` x-y box: the whole map for exploration, else where things happen."""
    if run.is_exploration and run.grid is not None:
        return run.grid.bounds_m[:, :2].copy()
    box = run.extent_m(pad=0.0, world=False)[:, :2]
    if run.grid is not None:  # do not zoom out to the whole town: pad by a link range
        pad = max(0.5 * run.range_m, 0.08 * float(np.max(box[1] - box[0])), 1.0)
        b = run.grid.bounds_m[:, :2]
        return np.stack([np.maximum(box[0] - pad, b[0]), np.minimum(box[1] + pad, b[1])])
    pad = max(0.08 * float(np.max(box[1] - box[0])), 1.0)
    return np.stack([box[0] - pad, box[1] + pad])


def _strip_series(run: RunData) -> tuple[str, np.ndarray, np.ndarray] | None:
    steps = run.steps
    if "step" not in steps:
        return None
    t = run.step_times_s(steps["step"])
    for col, label in (("n_links", "links"), ("explored_fraction", "explored fraction")):
        if col in steps:
            return label, t, np.asarray(steps[col], dtype=float)
    return None


class _Painter:
    """The figure of one run; :meth:`draw` updates it to frame ``k`` and returns RGB."""

    def __init__(self, run: RunData, width_in: float, dpi: int) -> None:
        self.run = run
        self.dpi = dpi
        box = _view_box(run)
        aspect = float((box[1, 1] - box[0, 1]) / max(box[1, 0] - box[0, 0], 1e-9))
        three_d = run.dim == 3
        strip = _strip_series(run)
        axes_w_in = width_in * 4 / 5.25 * 0.82  # the plots' column, less its labels
        ratios = [axes_w_in * max(min(aspect, 1.6), 0.35)]  # the top view at its own aspect
        if three_d:
            ratios.append(axes_w_in * 0.3)
        if strip is not None:
            ratios.append(axes_w_in * 0.2)
        height_in = sum(ratios) + 0.7 * len(ratios) + 0.3
        self.fig = plt.figure(figsize=(width_in, height_in), dpi=dpi)
        gs = self.fig.add_gridspec(len(ratios), 2, height_ratios=ratios, width_ratios=[4, 1.25])
        self.ax = self.fig.add_subplot(gs[0, 0])
        legend_ax = self.fig.add_subplot(gs[:, 1])
        legend_ax.set_axis_off()
        row = 1
        self.side = None
        if three_d:
            self.side = self.fig.add_subplot(gs[row, 0])
            row += 1
        self.strip_ax = self.fig.add_subplot(gs[row, 0]) if strip is not None else None

        self.first_seen, exact = first_seen(run) if run.is_exploration else (None, False)
        ax = self.ax
        style.label_axes(ax)
        known0 = None if self.first_seen is None else self.first_seen <= 0
        self.map_img = style.draw_obstacles_topdown(ax, run.grid, known=known0, colorbar=False)
        if run.grid is not None and run.grid.dim == 3 and self.map_img is not None:
            cax = legend_ax.inset_axes((0.0, 0.06, 0.12, 0.3))
            cb = self.fig.colorbar(self.map_img, cax=cax)
            cb.set_label("obstacle height (m)", fontsize=8)
            cb.ax.tick_params(labelsize=7)
        if len(run.link_pairs):  # beside the height bar, if there is one
            left = 0.55 if run.grid is not None and run.grid.dim == 3 else 0.0
            style.link_margin_colourbar(self.fig, cax=legend_ax.inset_axes((left, 0.06, 0.12, 0.3)))
        ax.set_xlim(box[0, 0], box[1, 0])
        ax.set_ylim(box[0, 1], box[1, 1])
        overlays = []  # drawn with the moving artists, in z order, over a changing map
        if run.planned_path_m is not None:
            p = run.planned_path_m
            overlays += ax.plot(p[:, 0], p[:, 1], ls="--", color=style.PATH, lw=1.4, zorder=2)
        self.target_dots = None
        if run.targets_m is not None:
            g = run.targets_m
            self.target_dots = ax.scatter(
                g[:, 0],
                g[:, 1],
                marker="*",
                s=160,
                c=style.TARGET,
                edgecolors=style.ROBOT_EDGE,
                zorder=5,
            )
            overlays.append(self.target_dots)
        if run.base_m is not None:
            base = ax.scatter(
                [run.base_m[0]],
                [run.base_m[1]],
                marker="s",
                s=90,
                c=style.BASE_STATION,
                edgecolors=style.ROBOT_EDGE,
                zorder=5,
            )
            overlays.append(base)
        self.overlays = overlays
        self.trails = LineCollection([], linewidths=0.8, colors="#555555", alpha=0.35, zorder=2)
        ax.add_collection(self.trails)
        self.links = LineCollection([], linewidths=1.3, zorder=3)
        ax.add_collection(self.links)
        self.dots = ax.scatter([], [], s=36, edgecolors=style.ROBOT_EDGE, linewidths=0.6, zorder=4)
        self.title = ax.set_title("t = 0 s", fontsize=10)
        if self.side is not None:
            style.draw_obstacles_side(self.side, run.grid, span_m=(box[0, 1], box[1, 1]))
            self.side.set_xlabel(style.X_LABEL)
            self.side.set_ylabel(style.Z_LABEL)
            self.side.set_facecolor(style.BACKGROUND)
            z = run.positions_m[:, :, 2]
            zlo = min(float(np.nanmin(z)), 0.0)
            ztop = float(np.nanmax(z))
            if run.grid is not None:
                ztop = max(ztop, float(run.grid.bounds_m[1, 2]))
            self.side.set_ylim(zlo, ztop + 0.5)
            self.side_links = LineCollection([], linewidths=1.0, zorder=3)
            self.side.add_collection(self.side_links)
            self.side_dots = self.side.scatter(
                [], [], s=24, edgecolors=style.ROBOT_EDGE, linewidths=0.5, zorder=4
            )
            self.side.set_title("side view", fontsize=8, loc="left")
        self.cursor = None
        if strip is not None and self.strip_ax is not None:
            label, t, y = strip
            self.strip_ax.plot(t, y, color="#444444", lw=1.0)
            self.strip_ax.set_xlabel("time (s)")
            self.strip_ax.set_ylabel(label)
            self.strip_ax.grid(alpha=0.3)
            self.cursor = self.strip_ax.axvline(0.0, color=style.CURSOR, lw=1.2)
        roles = run.roles
        self.role_map = style.role_colour_map(np.unique(roles)) if roles is not None else None
        handles = style.legend_handles(
            roles=self.role_map,
            leader=run.leader is not None,
            base_station=run.base_m is not None,
            exploration=run.connected is not None and roles is None,
            targets=run.targets_m is not None,
            targets_finished=run.targets is not None
            and bool(np.any(run.targets.finished_steps >= 0)),
            path=run.planned_path_m is not None,
            links=len(run.link_pairs) > 0,
            unknown=self.first_seen is not None,
        )
        legend_ax.legend(handles=handles, loc="upper left", fontsize=8, frameon=False)
        if self.first_seen is not None and not exact:
            legend_ax.text(
                0,
                0.02,
                "known map: seen by the\nrobots (approx.)",
                fontsize=7,
                transform=legend_ax.transAxes,
                color="#555555",
            )
        self.fig.tight_layout()
        if self.side is not None:  # the side view under the top view, same x scale
            self.ax.apply_aspect()
            top, side = self.ax.get_position(), self.side.get_position()
            self.side.set_position((top.x0, side.y0, top.width, side.height))
            self.side.set_xlim(self.ax.get_xlim())
        top_view = [*self.overlays, self.trails, self.links, self.dots]
        if self.first_seen is not None and self.map_img is not None:
            top_view.append(self.map_img)
        self.animated = [*sorted(top_view, key=lambda a: a.get_zorder()), self.title]
        if self.side is not None:
            self.animated += [self.side_links, self.side_dots]
        if self.cursor is not None:
            self.animated.append(self.cursor)
        for artist in self.animated:
            artist.set_animated(True)
        self.fig.canvas.draw()  # everything that does not move, once
        self.background = self.fig.canvas.copy_from_bbox(self.fig.bbox)

    def colours(self, k: int) -> np.ndarray:
        run = self.run
        roles = run.roles[k] if run.roles is not None else None
        conn = run.connected[k] if run.connected is not None else None
        return style.robot_colours(
            run.n_robots, roles=roles, role_map=self.role_map, leader=run.leader, connected=conn
        )

    def draw(self, k: int, shown: np.ndarray) -> np.ndarray:
        run = self.run
        pos = run.positions_m[k]
        nodes = run.nodes(k)
        lk = run.links(k)
        colours = self.colours(k)
        seg = np.stack([nodes[lk[:, 0], :2], nodes[lk[:, 1], :2]], axis=1) if len(lk) else []
        link_rgba = style.link_colours(run.link_margins(k)) if len(lk) else []
        self.links.set_segments(seg)
        self.links.set_colors(link_rgba)
        order = np.argsort(pos[:, 2]) if run.dim == 3 else np.arange(len(pos))
        self.dots.set_offsets(pos[order, :2])
        self.dots.set_facecolors(colours[order])
        if run.dim == 3:  # higher robots drawn larger and on top
            z = pos[order, 2]
            span = max(
                float(np.nanmax(run.positions_m[:, :, 2]) - np.nanmin(run.positions_m[:, :, 2])),
                1e-9,
            )
            self.dots.set_sizes(26 + 30 * (z - np.nanmin(run.positions_m[:, :, 2])) / span)
        past = shown[
            max(0, int(np.searchsorted(shown, k)) - TRAIL_FRAMES) : int(np.searchsorted(shown, k))
            + 1
        ]
        trail = run.positions_m[past][:, :, :2].transpose(1, 0, 2)
        self.trails.set_segments(list(trail) if len(past) > 1 else [])
        if self.first_seen is not None and self.map_img is not None:
            self.map_img.set_data(style.map_states(run.grid, self.first_seen <= k).T)
        if self.side is not None:
            xz = nodes[:, [0, 2]]
            self.side_dots.set_offsets(pos[:, [0, 2]])
            self.side_dots.set_facecolors(colours)
            self.side_links.set_segments(
                np.stack([xz[lk[:, 0]], xz[lk[:, 1]]], axis=1) if len(lk) else []
            )
            self.side_links.set_colors(link_rgba)
        t = float(run.frame_times_s[k])
        if run.targets is not None and self.target_dots is not None:
            self._show_targets(int(run.frame_steps[k]), t)
        self.title.set_text(f"{run.name}: t = {t:.1f} s (step {int(run.frame_steps[k])})")
        if self.cursor is not None:
            self.cursor.set_xdata([t, t])
        canvas = self.fig.canvas
        canvas.restore_region(self.background)
        for artist in self.animated:
            self.fig.draw_artist(artist)
        buf = np.asarray(self.fig.canvas.buffer_rgba())
        return np.ascontiguousarray(buf[:, :, :3])

    def _show_targets(self, step: int, t_s: float) -> None:
        """Targets added by now: filled while open, hollow once reached or dropped."""
        states = self.run.targets.states(step, t_s)
        shown = states != HIDDEN
        self.target_dots.set_offsets(self.run.targets_m[shown, :2])
        face = np.where(states[shown] == FINISHED, "none", style.TARGET)
        self.target_dots.set_facecolors(face.tolist())

    def close(self) -> None:
        plt.close(self.fig)


def _frames(painter: _Painter, shown: np.ndarray, progress: bool) -> Iterator[np.ndarray]:
    if not progress:
        for k in shown:
            yield painter.draw(int(k), shown)
        return
    with progress_bar("drawing frames") as bar:
        task = bar.add_task("animate", total=len(shown))
        for k in shown:
            yield painter.draw(int(k), shown)
            bar.advance(task)


def _write_gif(frames: Iterator[np.ndarray], out: Path, fps: float) -> tuple[int, tuple[int, int]]:
    images = []
    for rgb in frames:
        im = Image.fromarray(rgb)
        images.append(
            im.quantize(colors=128, method=Image.Quantize.FASTOCTREE, dither=Image.Dither.NONE)
        )
    if not images:
        raise TetherError("nothing to animate: the run has no recorded positions")
    images[0].save(
        out,
        format="GIF",
        save_all=True,
        append_images=images[1:],
        duration=int(round(1000 / fps)),
        loop=0,
        optimize=False,
        disposal=1,
    )
    return len(images), images[0].size


def _write_mp4(frames: Iterator[np.ndarray], out: Path, fps: float) -> tuple[int, tuple[int, int]]:
    ffmpeg = shutil.which("ffmpeg")
    if ffmpeg is None:
        raise TetherError("MP4 needs ffmpeg, which is not installed; use --format gif")
    proc: subprocess.Popen | None = None
    count, size = 0, (0, 0)
    try:
        for rgb in frames:
            if proc is None:
                size = (rgb.shape[1], rgb.shape[0])
                cmd = [
                    ffmpeg,
                    "-y",
                    "-loglevel",
                    "error",
                    "-f",
                    "rawvideo",
                    "-pix_fmt",
                    "rgb24",
                    "-s",
                    f"{size[0]}x{size[1]}",
                    "-r",
                    f"{fps:g}",
                    "-i",
                    "-",
                    "-vf",
                    "pad=ceil(iw/2)*2:ceil(ih/2)*2",
                    "-pix_fmt",
                    "yuv420p",
                    "-c:v",
                    "libx264",
                    "-movflags",
                    "+faststart",
                    "-f",
                    "mp4",
                    str(out),
                ]
                proc = subprocess.Popen(cmd, stdin=subprocess.PIPE, stderr=subprocess.PIPE)
            assert proc.stdin is not None
            proc.stdin.write(rgb.tobytes())
            count += 1
    finally:
        if proc is not None:
            _, stderr = proc.communicate()
            if proc.returncode != 0:
                raise TetherError(f"ffmpeg failed: {stderr.decode(errors='replace').strip()[:300]}")
    if count == 0:
        raise TetherError("nothing to animate: the run has no recorded positions")
    return count, size


def animate(
    run: RunData | str | Path,
    out: str | Path | None = None,
    *,
    fmt: str | None = None,
    fps: float = DEFAULT_FPS,
    duration_s: float | None = None,
    stride: int | None = None,
    width_px: int = 720,
    progress: bool = True,
) -> Animation:
    """Write an animation of a run folder.

    ``fmt`` is ``gif`` or ``mp4`` (default: from ``out``'s suffix, else gif); the
    frames are every ``stride``-th recorded step, or evenly thinned so that the
    animation lasts at most ``duration_s`` at ``fps`` (default 20 s); the last step
    is always shown. Output defaults to ``RUN_DIR/animation.<fmt>``.
    """
    start = time.perf_counter()
    if not isinstance(run, RunData):
        run = load_run(run)
    if fps <= 0:
        raise TetherError(f"--fps: must be positive (got {fps})")
    if fmt is None:
        fmt = Path(out).suffix.lstrip(".").lower() if out is not None else "gif"
        fmt = fmt if fmt in ("gif", "mp4") else "gif"
    fmt = fmt.lower()
    if fmt not in ("gif", "mp4"):
        raise TetherError(f"--format: expected gif or mp4 (got {fmt!r})")
    out_path = Path(out) if out is not None else run.path / f"animation.{fmt}"
    check_target(out_path)  # before any frame is drawn
    max_frames = int(max(1, round(fps * (duration_s or DEFAULT_DURATION_S))))
    shown = frame_indices(run.n_frames, stride=stride, max_frames=None if stride else max_frames)
    dpi = 90
    painter = _Painter(run, width_px / dpi, dpi)
    try:
        frames = _frames(painter, shown, progress)
        writer = _write_gif if fmt == "gif" else _write_mp4
        written: list[tuple[int, tuple[int, int]]] = []
        n_bytes = write_output(out_path, lambda tmp: written.append(writer(frames, Path(tmp), fps)),
                               what="animation", run_dir=run.path)  # fmt: skip
    finally:
        painter.close()
    count, size = written[0]
    return Animation(out_path, fmt, count, size, n_bytes, time.perf_counter() - start)
