"""The static figures of run folders and sweeps are in the one look (``viz/style.py``).

Short runs of every built-in strategy are drawn with ``tether.runner.run_figures``
(exactly what ``tether run`` writes into ``figures/``) and read back as pixels and
artists: axes in metres and seconds, legends naming the leader, the roles and the
base station, obstacles (3-D buildings as footprints shaded by height, with a side
view), links coloured by margin, and the three map classes of exploration runs
(free, occupied, unknown) in distinct colours.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.colors import to_rgb  # noqa: E402

from _viewing_helpers import make_run_folder  # noqa: E402
from tether.config import load_scenario, scenario_from_dict  # noqa: E402
from tether.experiments.sweep import sweep_figures  # noqa: E402
from tether.plugins import load_builtins  # noqa: E402
from tether.record import TrajectoryRecorder  # noqa: E402
from tether.recurrent.figures import known_map  # noqa: E402
from tether.registry import STRATEGIES  # noqa: E402
from tether.runner import build, run_figures  # noqa: E402
from tether.sim import simulate  # noqa: E402
from tether.viz import style  # noqa: E402
from tether.viz.plots import snapshot  # noqa: E402
from tether.world.grid import OccupancyGrid  # noqa: E402
from tether.world.world import World  # noqa: E402

load_builtins()

ROOT = Path(__file__).resolve().parents[1]
EXPLORATION = {
    "recurrent", "utility", "unconstrained", "silent_exploration", "continuous_exploration"
}  # fmt: skip
_UTILITY = {
    "name": "utility",
    "params": {"speed_m_s": 0.4, "comm_range_m": 15.0, "fov_deg": 60.0, "ratio": 0.5},
}
# strategy -> (built-in scenario, steps, overrides): short runs, a few seconds each
RUNS: dict[str, tuple[str, int, dict[str, Any]]] = {
    "silent": ("silent_demo", 20, {}),
    "connectivity": ("connectivity_town", 6, {}),
    "multi_target": ("multi_target_office", 10, {"output": {"record_every": 1}}),
    "recurrent": ("recurrent_demo", 20, {}),
    "utility": ("recurrent_demo", 20, {"strategy": _UTILITY}),
    "unconstrained": ("mission_unconstrained", 20, {}),
    "silent_exploration": ("mission_silent", 20, {}),
    "continuous_exploration": ("mission_continuous", 20, {}),
}
DPI = 60


class Drawn:
    """A short run's figures (matplotlib objects) with what made them."""

    def __init__(self, strategy: str) -> None:
        name, steps, overrides = RUNS[strategy]
        base = load_scenario(name)
        data = base.model_dump(mode="json")
        data["sim"]["max_steps"] = steps
        for key, value in overrides.items():
            data[key] = {**data[key], **value} if key != "strategy" else value
        sc = scenario_from_dict(data, name, base.base_dir)
        self.built = build(sc)
        self.recorder = TrajectoryRecorder(every=sc.output.record_every)
        b = self.built
        simulate(b.world, b.sensor, b.strategy, b.initial, dt_s=sc.sim.dt_s, max_steps=steps,
                 rng=b.rng, collision_distance_m=sc.sim.collision_distance_m,
                 recorder=self.recorder)  # fmt: skip
        self.figures = run_figures(b, self.recorder)
        self._pixels: dict[str, np.ndarray] = {}

    def pixels(self, name: str) -> np.ndarray:
        if name not in self._pixels:
            self._pixels[name] = render(self.figures[name])
        return self._pixels[name]


@pytest.fixture(scope="module")
def drawn():
    cache: dict[str, Drawn] = {}

    def get(strategy: str) -> Drawn:
        if strategy not in cache:
            cache[strategy] = Drawn(strategy)
        return cache[strategy]

    yield get
    for d in cache.values():
        for fig in d.figures.values():
            plt.close(fig)


def render(fig: Any, dpi: int = DPI) -> np.ndarray:
    """The figure as ``(h, w, 3)`` RGB integers, as a PNG of it would hold."""
    fig.set_dpi(dpi)
    fig.canvas.draw()
    return np.asarray(fig.canvas.buffer_rgba())[:, :, :3].astype(int)


def near(img: np.ndarray, colour: Any, tol: int = 10) -> np.ndarray:
    target = np.asarray(to_rgb(colour) if isinstance(colour, str) else colour[:3]) * 255
    return np.abs(img - target).max(axis=-1) <= tol


def at(img: np.ndarray, ax: Any, xy: tuple[float, float], r: int = 0) -> np.ndarray:
    """Pixels ``(k, 3)`` within ``r`` of data point ``xy`` of ``ax`` (after :func:`render`)."""
    px, py = ax.transData.transform(xy)
    row, col = int(round(img.shape[0] - py)), int(round(px))
    return img[row - r : row + r + 1, col - r : col + r + 1].reshape(-1, 3)


def legend_texts(fig: Any) -> list[str]:
    legends = list(fig.legends) + [ax.get_legend() for ax in fig.axes if ax.get_legend()]
    return [t.get_text() for lg in legends for t in lg.get_texts()]


def top_views(fig: Any) -> list[Any]:
    return [ax for ax in fig.axes if ax.get_ylabel() == "y (m)"]


def builtin_strategies() -> set[str]:
    return {n for n in STRATEGIES.names() if STRATEGIES.get(n).__module__.startswith("tether.")}


def readme_figures() -> str:
    """The figures the run folder reference lists (docs/reference/run-folder.md)."""
    text = (ROOT / "docs" / "reference" / "run-folder.md").read_text()
    return text.split("figures/", 1)[1].split("\n", 1)[0]


def test_every_builtin_strategy_is_drawn_here():
    assert builtin_strategies() == set(RUNS)


@pytest.mark.parametrize("strategy", sorted(RUNS))
def test_figures_have_units_titles_legends_and_match_the_readme(strategy, drawn):
    d = drawn(strategy)
    names = set(d.figures)
    expected = {"links.png", "snapshot.png"} | (
        {"explored.png", "map.png"} if strategy in EXPLORATION else set()
    )
    assert names == expected
    listed = readme_figures()
    assert all(n in listed for n in names), f"docs/reference/run-folder.md lacks one of {names}"
    snap = d.figures["snapshot.png"]
    tops = top_views(snap)
    assert len(tops) == 3 and all(ax.get_xlabel() == "x (m)" for ax in tops)
    assert all(re.fullmatch(r"t = [\d.]+ s", ax.get_title()) for ax in tops)
    assert snap._suptitle is not None and snap._suptitle.get_text()
    texts = legend_texts(snap)
    assert any(t.startswith("robot") for t in texts)
    assert {"link, strong", "link, near range"} <= set(texts), "links not coloured by margin"
    links = d.figures["links.png"].axes[0]
    assert links.get_xlabel() == "time (s)" and links.get_title()
    assert any(t.startswith("spanning tree") for t in legend_texts(d.figures["links.png"]))
    if d.built.world.dim == 3:
        sides = [ax for ax in snap.axes if ax.get_ylabel() == "z (m)"]
        assert len(sides) == 3 and all(ax.get_xlabel() == "x (m)" for ax in sides)
        for top, side in zip(tops, sides, strict=True):  # the same x scale, one above the other
            t, s = top.get_position(), side.get_position()
            assert abs(t.x0 - s.x0) < 1e-6 and abs(t.width - s.width) < 1e-6
            assert top.get_xlim() == pytest.approx(side.get_xlim())
    if d.built.world.has_obstacles:
        kind = "building / wall (darker: taller)" if d.built.world.dim == 3 else "obstacle / wall"
        assert kind in texts


def test_silent_snapshot_marks_the_leader_and_its_path(drawn):
    d = drawn("silent")
    texts = legend_texts(d.figures["snapshot.png"])
    assert "leader" in texts and "leader's path" in texts
    img = d.pixels("snapshot.png")
    assert near(img, style.LEADER).sum() > 3 * 20, "the leader is not drawn in every panel"
    assert near(img, style.PATH, tol=30).sum() > 100, "no path"
    leader = d.built.strategy.leader
    n = len(d.recorder.positions)
    for ax, i in zip(top_views(d.figures["snapshot.png"]), sorted({0, n // 2, n - 1}), strict=True):
        pos = d.recorder.positions[i][leader]
        assert near(at(img, ax, tuple(pos[:2]), r=1), style.LEADER, tol=25).any()


def test_multi_target_robots_are_coloured_by_role(drawn):
    d = drawn("multi_target")
    n = len(d.recorder.positions)
    shown = sorted({0, n // 2, n - 1})
    roles = sorted({str(r) for i in shown for r in d.recorder.robot_values[i]["role"]})
    assert len(roles) >= 2
    texts = legend_texts(d.figures["snapshot.png"])
    assert {f"robot: {r}" for r in roles} <= set(texts)
    img = d.pixels("snapshot.png")
    colours = style.role_colour_map(roles)
    for ax, i in zip(top_views(d.figures["snapshot.png"]), shown, strict=True):
        role, pos = d.recorder.robot_values[i]["role"], d.recorder.positions[i]
        hits = [near(at(img, ax, tuple(pos[k, :2]), r=1), colours[str(role[k])], tol=30).any()
                for k in range(len(pos))]  # fmt: skip
        assert np.mean(hits) > 0.5, "robots not drawn in their role's colour"


def test_town_snapshot_shows_buildings_by_height_and_a_side_view(drawn):
    d = drawn("connectivity")
    fig = d.figures["snapshot.png"]
    grid = d.built.world.grid
    assert any(ax.get_ylabel() == "obstacle height (m)" for ax in fig.axes)
    img = d.pixels("snapshot.png")
    heights, _ = style.height_map(grid)
    ax = top_views(fig)[0]
    (x0, x1), (y0, y1) = ax.get_xlim(), ax.get_ylim()
    full = heights > 0
    inner = full[1:-1, 1:-1] & full[:-2, 1:-1] & full[2:, 1:-1] & full[1:-1, :-2] & full[1:-1, 2:]
    cells = np.argwhere(inner) + 1
    centres = grid.origin_m[:2] + (cells + 0.5) * grid.resolution_m
    inside = (
        (centres[:, 0] > x0) & (centres[:, 0] < x1) & (centres[:, 1] > y0) & (centres[:, 1] < y1)
    )
    assert inside.sum() >= 10, "the view holds no building"
    top = float(grid.bounds_m[1, 2] - grid.bounds_m[0, 2])
    rng = np.random.default_rng(0)
    checked = 0
    for k in rng.choice(np.flatnonzero(inside), size=min(30, int(inside.sum())), replace=False):
        expected = style.HEIGHT_CMAP(heights[tuple(cells[k])] / top)
        got = at(img, ax, tuple(centres[k]))
        robots_or_links = near(got, style.ROBOT, tol=60).any()
        if not robots_or_links:
            assert near(got, expected, tol=12).all(), "a building is not drawn at its place"
            checked += 1
    assert checked >= 5
    assert near(img, style.BACKGROUND, tol=3).sum() > 1000, "free space not told apart"


def test_exploration_figures_mark_the_base_station_and_three_map_classes(drawn):
    d = drawn("recurrent")
    snap_texts = legend_texts(d.figures["snapshot.png"])
    assert "base station" in snap_texts and "robot, connected to BS" in snap_texts
    assert near(d.pixels("snapshot.png"), style.BASE_STATION).sum() > 3 * 20
    base = d.recorder.fixed[0]
    top = top_views(d.figures["snapshot.png"])[0]
    segments = [s for c in top.collections if hasattr(c, "get_segments")
                for s in c.get_segments()]  # fmt: skip
    assert any(np.allclose(s[1], base[:2]) or np.allclose(s[0], base[:2]) for s in segments), (
        "no link to the base station drawn"
    )
    fig = d.figures["map.png"]
    ax = fig.axes[0]
    assert ax.get_xlabel() == "x (m)" and ax.get_ylabel() == "y (m)" and ax.get_title()
    texts = legend_texts(fig)
    for entry in ("base station", "free (known)", "occupied (known)", "unknown", "robot trail"):
        assert entry in texts
    img = d.pixels("map.png")
    colours = [style.FREE, style.OCCUPIED, style.UNKNOWN, style.UNKNOWN_OCCUPIED]
    rgb = np.array([to_rgb(c) for c in colours]) * 255
    assert min(np.abs(a - b).max() for i, a in enumerate(rgb) for b in rgb[i + 1 :]) > 40
    for c in colours:
        assert near(img, c, tol=4).sum() > 200, f"no {c} cells in map.png"
    assert near(img, style.BASE_STATION).sum() > 20
    explored = d.figures["explored.png"]
    eax = explored.axes[0]
    assert eax.get_xlabel() == "time (s)" and eax.get_ylabel() == "explored area (%)"
    assert eax.get_title() and len(legend_texts(explored)) == 2


def test_known_map_colours_each_cell_by_what_the_base_station_knows():
    """Left half known, right half not; a wall across both: four colours at four places."""
    occ = np.zeros((40, 20), dtype=bool)
    occ[:, 9:11] = True  # a wall at y = 9..11 m
    known = np.zeros_like(occ)
    known[:20] = True
    grid = OccupancyGrid(occ, 1.0)
    trails = np.array([[[5.5, 3.5], [30.5, 15.5]], [[6.5, 4.5], [31.5, 16.5]]])
    fig = known_map(grid, known, trails, np.array([2.5, 2.5]), connected=np.array([True, False]))
    img = render(fig)
    ax = fig.axes[0]
    places = {
        (12.5, 5.5): style.FREE,
        (12.5, 10.0): style.OCCUPIED,
        (25.5, 5.5): style.UNKNOWN,
        (25.5, 10.0): style.UNKNOWN_OCCUPIED,
    }
    for xy, colour in places.items():
        assert near(at(img, ax, xy, r=1), colour, tol=4).all(), (xy, colour)
    assert near(at(img, ax, (2.5, 2.5), r=1), style.BASE_STATION).any()
    assert near(at(img, ax, (31.5, 16.5), r=1), style.DISCONNECTED, tol=20).any()
    plt.close(fig)


def test_links_are_coloured_by_margin_and_robots_at_two_heights_stay_apart():
    world = World(dim=3, bounds_m=np.array([[-5.0, -5.0, 0.0], [15.0, 5.0, 10.0]]))
    pos = np.array([[0.0, 0.0, 2.0], [1.0, 0.0, 2.0], [9.5, 0.0, 2.0], [0.0, 0.0, 8.0]])
    links = np.array([[0, 1], [1, 2]])
    fig = snapshot([pos], [links], ["t = 0 s"], world=world, range_m=9.0)
    img = render(fig, dpi=100)
    top = top_views(fig)[0]
    side = next(ax for ax in fig.axes if ax.get_ylabel() == "z (m)")

    def link_pixels(xy: tuple[float, float]) -> np.ndarray:  # thin lines: blended at edges
        px = at(img, top, xy, r=2)
        return px[~near(px, style.BACKGROUND, tol=20)]

    strong, weak = link_pixels((0.5, 0.0)), link_pixels((5.25, 0.0))
    assert len(strong) and np.all(strong[:, 1] - strong[:, 0] > 30), "a short link is not green"
    assert len(weak) and np.all(weak[:, 0] - weak[:, 1] > 30), "a link near range is not red"
    assert near(at(img, side, (0.0, 2.0), r=1), style.ROBOT, tol=20).any()
    assert near(at(img, side, (0.0, 8.0), r=1), style.ROBOT, tol=20).any()
    assert "world boundary" in legend_texts(fig)
    plt.close(fig)


def test_sweep_figures_have_titles_units_and_a_line_per_combination(tmp_path):
    rows = []
    for k, d0 in enumerate((5.0, 8.0)):
        make_run_folder(tmp_path / f"r{k}", n_robots=4, n_steps=10, seed=k)
        rows.append({"param:strategy.params.d0_m": d0, "run_dir": str(tmp_path / f"r{k}")})
    [(fig, name)] = sweep_figures(rows, 4, "demo")
    ax = fig.axes[0]
    assert name == "links.png" and ax.get_xlabel() == "time (s)"
    assert ax.get_title().startswith("demo: number of links")
    texts = legend_texts(fig)
    assert len([t for t in texts if "d0_m" in t]) == 2 and "spanning tree (3 links)" in texts
    plt.close(fig)
