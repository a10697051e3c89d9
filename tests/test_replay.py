"""The replay page without a browser: payload encoding, size budget, self-containment, --serve."""

from __future__ import annotations

import base64
import gzip
import hashlib
import json
import re
import threading
import urllib.error
import urllib.request
from importlib import resources

import numpy as np
import pytest

from _viewing_helpers import make_run_folder
from tether.errors import TetherError
from tether.viewing.payload import MISSING
from tether.viewing.replay import THREE_SHA256, make_server, three_script, write_replay
from tether.viewing.runfolder import load_run
from tether.viz import style


def _page_data(html: str) -> tuple[dict, dict[str, np.ndarray]]:
    """Decode the page's embedded run as the page's script does."""
    meta = json.loads(re.search(r'id="tether-meta">(.*?)</script>', html, re.S).group(1))
    blob = re.search(r'id="tether-data">(.*?)</script>', html, re.S).group(1).strip()
    raw = gzip.decompress(base64.b64decode(blob))
    arrays = {}
    for a in meta["arrays"]:
        dt = np.dtype(a["dtype"])
        arrays[a["name"]] = np.frombuffer(raw, dt, a["length"], a["offset"]).reshape(a["shape"])
    return meta, arrays


def _positions(meta: dict, arrays: dict) -> np.ndarray:
    """(F, n, 3) metres from the uint16 frame differences (wrapping, as in JavaScript)."""
    q = np.cumsum(arrays["pos"].astype(np.uint64), axis=2) % 65536  # (3, n, F)
    lo, scale = np.asarray(meta["quant"]["lo"]), np.asarray(meta["quant"]["scale"])
    pos = lo[:, None, None] + q * scale[:, None, None]
    pos[q == MISSING] = np.nan
    return pos.transpose(2, 1, 0)


def test_embedded_positions_and_links_are_the_recorded_ones(tmp_path):
    rec = make_run_folder(tmp_path / "run", n_robots=7, n_steps=120, dim=3, roles=True)
    html = write_replay(tmp_path / "run", tmp_path / "r.html").path.read_text()
    meta, arrays = _page_data(html)
    assert meta["n_frames"] == 121 and meta["stride"] == 1
    np.testing.assert_allclose(_positions(meta, arrays), rec["positions"], atol=0.005)
    assert np.array_equal(np.diff(arrays["link_off"]), rec["n_links"])
    assert [s["name"] for s in meta["series"]] == ["lambda2", "n_links"]
    assert set(meta["colours"]["names"]) == {"robot: leader", "robot: relay", "robot: explorer"}
    leader = meta["colours"]["names"].index("robot: leader")
    assert meta["colours"]["hex"][leader] == style.LEADER


def test_35_robots_10000_steps_under_10_mb_and_budget_thins(tmp_path):
    make_run_folder(tmp_path / "run", n_robots=35, n_steps=10_000, dim=3, range_m=8.0)
    full = write_replay(tmp_path / "run", tmp_path / "full.html")
    assert full.bytes < 10_000_000
    assert full.stride == 1 and full.n_frames == 10_001  # fits without thinning
    small = write_replay(tmp_path / "run", tmp_path / "small.html", budget_bytes=1_500_000)
    assert small.bytes <= 1_500_000
    assert small.stride > 1 and small.n_frames < 10_001
    meta, arrays = _page_data(small.path.read_text())
    steps = arrays["frame_steps"]
    assert steps[-1] == 10_000, "the last step is always shown"
    assert np.all(np.diff(steps)[:-1] == small.stride)
    # side plots stay at full rate (up to 20,000 points) whatever the thinning
    assert len(arrays["series_t"]) == 10_001


def test_page_is_self_contained():
    page = three_script()
    assert page.startswith("var THREE=(function()") and "return{" in page
    assert "export{" not in page
    template = resources.files("tether.viewing").joinpath("web", "replay.html").read_text()
    assert "Content-Security-Policy" in template and "default-src 'none'" in template
    assert not re.search(r"<(script|link|img)[^>]+(src|href)=", template)
    vendored = resources.files("tether.viewing").joinpath("vendor", "three.module.min.js")
    assert hashlib.sha256(vendored.read_bytes()).hexdigest() == THREE_SHA256


def test_world_is_embedded_for_2d_maps_and_3d_scenes(tmp_path):
    from tether.config import load_scenario
    from tether.runner import run

    sc = load_scenario("connectivity_office")
    sc.sim.max_steps = 5
    sc.output.figures = False
    out = run(sc, out_dir=tmp_path / "office").path
    meta, arrays = _page_data(write_replay(out, tmp_path / "o.html").path.read_text())
    assert meta["world"]["kind"] == "boxes" and meta["world"]["n"] == len(arrays["boxes"]) > 4
    grid = load_run(out).grid
    # every box lies inside the grid and the boxes' volume is the occupied volume
    boxes = arrays["boxes"].reshape(-1, 6)
    assert np.all(boxes[:, :3] >= grid.bounds_m[0] - 1e-6)
    assert np.all(boxes[:, 3:] <= grid.bounds_m[1] + 1e-6)
    volume = np.prod(boxes[:, 3:] - boxes[:, :3], axis=1).sum()
    assert volume == pytest.approx(grid.occupied.sum() * grid.resolution_m**3, rel=1e-3)


def test_serve_binds_loopback_and_serves_only_the_page(tmp_path):
    make_run_folder(tmp_path / "run", n_steps=10)
    page = write_replay(tmp_path / "run").path
    server = make_server(page, 0)
    assert server.server_address[0] == "127.0.0.1"
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    try:
        base = f"http://127.0.0.1:{server.server_address[1]}"
        with urllib.request.urlopen(base + "/", timeout=10) as resp:
            assert resp.status == 200
            assert b'id="tether-meta"' in resp.read()
        with urllib.request.urlopen(f"{base}/{page.name}", timeout=10) as resp:
            assert resp.status == 200
        with pytest.raises(urllib.error.HTTPError) as err:
            urllib.request.urlopen(base + "/summary.json", timeout=10)
        assert err.value.code == 404
    finally:
        server.shutdown()
        server.server_close()


def test_bad_inputs_are_one_line_errors(tmp_path):
    with pytest.raises(TetherError, match="not a run folder"):
        write_replay(tmp_path / "missing")
    make_run_folder(tmp_path / "run", n_steps=5)
    with pytest.raises(TetherError, match="too small"):
        write_replay(tmp_path / "run", budget_bytes=10_000)
