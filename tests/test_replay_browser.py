"""End to end: the replay page opened from file:// in headless Chromium (Playwright).

The page must draw the recorded run, follow its slider, toggle its layers, show
its side plots, and never touch the network. Chromium is Debian's ``chromium``
(``.ci/run`` installs it); Playwright drives it through ``executable_path`` and
never downloads a browser of its own. Only a machine with no Chromium skips.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from _tools import skip_unless_required
from _viewing_helpers import make_run_folder
from tether.viewing.replay import write_replay

CHROMIUM_ARGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
    "--enable-unsafe-swiftshader",  # WebGL in software, with no GPU
]


def _chromium() -> str | None:
    for name in ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable"):
        found = shutil.which(name)
        if found:
            return found
    return "/usr/bin/chromium" if Path("/usr/bin/chromium").exists() else None


@pytest.fixture(scope="module")
def browser():
    exe = _chromium()
    if exe is None:
        skip_unless_required("no Chromium found (apt-get install chromium; .ci/run does it)")
    from playwright.sync_api import sync_playwright

    with sync_playwright() as pw:
        b = pw.chromium.launch(executable_path=exe, args=CHROMIUM_ARGS)
        yield b
        b.close()


class Page:
    """A replay page with every request, console error and page error recorded."""

    def __init__(self, browser, html: Path) -> None:
        self.url = html.resolve().as_uri()
        # bypass_csp: the page's own Content-Security-Policy forbids every fetch (and the
        # test's string evaluations); lifted here so that any request the page tries is
        # actually made and seen below, not silently blocked
        self.page = browser.new_page(viewport={"width": 1100, "height": 700}, bypass_csp=True)
        self.requests: list[str] = []
        self.errors: list[str] = []
        self.page.on("request", lambda r: self.requests.append(r.url))
        self.page.on("pageerror", lambda e: self.errors.append(f"pageerror: {e}"))
        self.page.on("console", lambda m: self.errors.append(m.text) if m.type == "error" else None)
        self.page.goto(self.url)
        self.page.wait_for_function("window.tether && (window.tether.ready || window.tether.error)")
        assert self.page.evaluate("window.tether.error") is None

    def js(self, expr: str):
        return self.page.evaluate(expr)

    def markers(self) -> np.ndarray:
        return np.asarray(self.js("window.tether.markerPositions()"), dtype=float)

    def canvas_png(self, selector: str) -> bytes:
        return self.page.locator(selector).screenshot()

    def close(self) -> None:
        self.page.close()


def _recorded(run_dir: Path) -> tuple[np.ndarray, np.ndarray]:
    t = pq.read_table(run_dir / "robots.parquet").to_pydict()
    steps = np.unique(t["step"])
    n = max(t["robot"]) + 1
    pos = np.zeros((len(steps), n, 3))
    for s, r, x, y, z in zip(
        t["step"],
        t["robot"],
        t["x_m"],
        t["y_m"],
        t.get("z_m", [0.0] * len(t["step"])),
        strict=True,
    ):
        pos[np.searchsorted(steps, s), r] = (x, y, z)
    return steps, pos


def test_slider_moves_markers_plots_follow_and_no_network(browser, tmp_path):
    run_dir = tmp_path / "run"
    make_run_folder(run_dir, n_robots=9, n_steps=80, dim=3, range_m=10.0, roles=True)
    html = write_replay(run_dir, tmp_path / "replay.html").path
    steps, recorded = _recorded(run_dir)
    page = Page(browser, html)
    try:
        assert page.js("window.tether.webgl") is True, "no WebGL: the 3-D view did not start"
        assert page.js("window.tether.nFrames") == len(steps)
        before = page.markers()
        # markers are drawn where the run folder says, to the quantization (< 1 cm)
        np.testing.assert_allclose(before, recorded[0], atol=0.01)
        view_before = page.canvas_png("#view canvas")
        plot_before = page.js("document.getElementById('plot-lambda2').toDataURL()")

        k = 61
        page.page.fill("#slider", str(k))
        assert page.js("window.tether.frame") == k
        after = page.markers()
        assert np.linalg.norm(after - before, axis=1).min() > 0.05, "some markers did not move"
        np.testing.assert_allclose(after, recorded[k], atol=0.01)
        link_steps = np.asarray(pq.read_table(run_dir / "links.parquet")["step"])
        assert page.js("window.tether.drawnLinks()") == int(np.sum(link_steps == steps[k]))
        assert page.canvas_png("#view canvas") != view_before, "the 3-D view was not redrawn"

        # side plots: lambda2 and link count exist, are drawn, and their cursor follows
        for name in ("lambda2", "n_links"):
            box = page.page.locator(f"#plot-{name}").bounding_box()
            assert box is not None and box["width"] > 100 and box["height"] > 50
            inked = page.js(
                f"""(() => {{ const c = document.getElementById('plot-{name}');
                const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
                let k = 0; for (let i = 3; i < d.length; i += 4) if (d[i] > 0) k++;
                return k; }})()"""
            )
            assert inked > 500, f"side plot {name} is blank"
        assert page.js("document.getElementById('plot-lambda2').toDataURL()") != plot_before
        assert "step 61" in page.page.inner_text("#time")

        assert page.requests == [page.url], f"network requests: {page.requests[1:]}"
        assert page.errors == []
    finally:
        page.close()


def test_toggles_play_and_orbit(browser, tmp_path):
    run_dir = tmp_path / "run"
    make_run_folder(run_dir, n_robots=6, n_steps=400, dim=2)
    page = Page(browser, write_replay(run_dir, tmp_path / "r.html").path)
    try:
        assert page.js("window.tether.visibility()") == {
            "links": True,
            "paths": True,
            "obstacles": None,
        }
        page.page.uncheck("#show-links")
        page.page.uncheck("#show-paths")
        assert page.js("window.tether.visibility()")["links"] is False
        assert page.js("window.tether.visibility()")["paths"] is False
        page.page.check("#show-links")
        assert page.js("window.tether.visibility()")["links"] is True

        page.page.click("#play")
        page.page.wait_for_function("window.tether.frame >= 5")
        page.page.click("#play")
        assert page.js("window.tether.playing()") is False
        stopped = page.js("window.tether.frame")
        page.page.wait_for_timeout(300)
        assert page.js("window.tether.frame") == stopped, "pause did not stop the replay"

        # orbit: dragging on the view turns the camera (the picture changes)
        shot = page.canvas_png("#view canvas")
        box = page.page.locator("#view canvas").bounding_box()
        cx, cy = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
        page.page.mouse.move(cx, cy)
        page.page.mouse.down()
        page.page.mouse.move(cx + 150, cy + 40, steps=5)
        page.page.mouse.up()
        assert page.canvas_png("#view canvas") != shot
        assert page.requests == [page.url]
        assert page.errors == []
    finally:
        page.close()


def test_exploration_map_fills_in_as_robots_explore(browser, tmp_path):
    from tether.config import load_scenario
    from tether.runner import run

    sc = load_scenario("recurrent_demo")
    sc.sim.max_steps = 60
    sc.output.figures = False
    out = run(sc, out_dir=tmp_path / "run").path
    page = Page(browser, write_replay(out, tmp_path / "r.html").path)
    try:
        meta = page.js("window.tether.meta")
        assert meta["world"]["kind"] == "map" and meta["base_m"] is not None
        unknown0 = page.js("window.tether.unknownCells()")
        page.js(f"window.tether.show({meta['n_frames'] - 1})")
        unknown1 = page.js("window.tether.unknownCells()")
        assert 0 < unknown1 < unknown0, (unknown0, unknown1)
        assert page.requests == [page.url]
        assert page.errors == []
    finally:
        page.close()


def test_links_to_the_base_station_end_at_it(browser, tmp_path):
    """After the core refactor exploration runs record links; index n_robots is the BS."""
    import json

    import pyarrow as pa

    run_dir = tmp_path / "run"
    make_run_folder(run_dir, n_robots=4, n_steps=6, dim=2)
    summary = json.loads((run_dir / "summary.json").read_text())
    summary["base_m"] = [-30.0, 12.5]
    (run_dir / "summary.json").write_text(json.dumps(summary))
    links = {"step": [0, 0, 3], "i": [0, 1, 2], "j": [4, 2, 4]}  # 4 = the base station
    pq.write_table(pa.table(links), run_dir / "links.parquet")
    page = Page(browser, write_replay(run_dir, tmp_path / "r.html").path)
    try:
        assert page.js("window.tether.drawnLinks()") == 2
        ends = np.asarray(page.js("window.tether.linkEnds()")).reshape(-1, 3)
        assert np.any(np.all(np.abs(ends[:, :2] - [-30.0, 12.5]) < 1e-3, axis=1))
        page.page.fill("#slider", "3")
        ends = np.asarray(page.js("window.tether.linkEnds()")).reshape(-1, 3)
        assert len(ends) == 2 and np.allclose(ends[1, :2], [-30.0, 12.5], atol=1e-3)
        assert page.errors == []
    finally:
        page.close()
