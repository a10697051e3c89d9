"""``tether animate``: frames chosen by fps / duration / stride, the one look in the pixels,
GIF and MP4 outputs, and the CLI shortcuts (``tether animate``, ``tether run --animate``)."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from matplotlib.colors import to_rgb
from PIL import Image

from _tools import skip_unless_required
from tether.config import load_scenario
from tether.errors import TetherError
from tether.runner import run
from tether.viewing.animate import animate
from tether.viz import style


def _run(name: str, root: Path, steps: int) -> Path:
    sc = load_scenario(name)
    sc.sim.max_steps = steps
    sc.output.figures = False
    return run(sc, out_dir=root / name).path


@pytest.fixture(scope="module")
def silent(tmp_path_factory) -> Path:
    return _run("silent_demo", tmp_path_factory.mktemp("silent"), 40)


def _frames(path: Path) -> list[np.ndarray]:
    im = Image.open(path)
    out = []
    for k in range(im.n_frames):
        im.seek(k)
        out.append(np.asarray(im.convert("RGB"), dtype=int))
    return out


def _count(frame: np.ndarray, colour: str, tol: int = 18) -> int:
    rgb = np.round(np.asarray(to_rgb(colour)) * 255)
    return int(np.sum(np.all(np.abs(frame - rgb) <= tol, axis=2)))


def test_gif_frames_follow_fps_and_duration_and_show_leader_and_path(silent, tmp_path):
    a = animate(silent, tmp_path / "a.gif", fps=10, duration_s=2.0, progress=False)
    # 41 recorded steps thinned to at most 20 frames: every 3rd, plus the last
    assert a.format == "gif" and a.n_frames == 15
    im = Image.open(a.path)
    assert im.n_frames == 15 and im.info["duration"] == 100
    frames = _frames(a.path)
    assert np.abs(frames[0] - frames[-1]).sum() > 0, "the team did not move in the animation"
    first = frames[0][:, : int(0.7 * frames[0].shape[1])]  # the plots, not the legend
    assert _count(first, style.LEADER) > 20, "the leader is not drawn (magenta)"
    assert _count(first, style.PATH) > 50, "the planned path is not drawn"
    assert _count(first, style.ROBOT) > 50, "the followers are not drawn"


def test_stride_and_mp4(silent, tmp_path):
    a = animate(silent, tmp_path / "s.gif", stride=10, progress=False)
    assert a.n_frames == 5  # steps 0, 10, 20, 30, 40
    if shutil.which("ffmpeg") is None:
        skip_unless_required("ffmpeg not installed: MP4 not tested")
    m = animate(silent, tmp_path / "m.mp4", stride=4, fps=5, progress=False)
    assert m.format == "mp4" and m.n_frames == 11
    head = m.path.read_bytes()[:12]
    assert head[4:8] == b"ftyp"
    if shutil.which("ffprobe"):
        probe = subprocess.run(
            [
                "ffprobe",
                "-v",
                "error",
                "-count_frames",
                "-select_streams",
                "v:0",
                "-show_entries",
                "stream=nb_read_frames",
                "-of",
                "csv=p=0",
                str(m.path),
            ],
            capture_output=True,
            text=True,
            timeout=60,
        )
        assert int(probe.stdout.strip()) == 11


def test_mp4_without_ffmpeg_is_a_one_line_error(silent, tmp_path, monkeypatch):
    monkeypatch.setattr(shutil, "which", lambda name: None)
    with pytest.raises(TetherError, match="ffmpeg"):
        animate(silent, tmp_path / "x.mp4", stride=20, progress=False)
    with pytest.raises(TetherError, match="gif or mp4"):
        animate(silent, tmp_path / "x.avi", fmt="avi", progress=False)


def test_town_shows_buildings_by_height_and_a_side_view(tmp_path):
    town = _run("connectivity_town", tmp_path, 10)
    a = animate(town, tmp_path / "t.gif", stride=5, progress=False)
    frame = _frames(a.path)[0]
    shades = [style.HEIGHT_CMAP(u) for u in np.linspace(0.15, 1.0, 12)]
    building = sum(_count(frame, shade, tol=10) for shade in shades)
    assert building > 2000, "no buildings drawn"
    side = _count(frame, style.UNKNOWN_OCCUPIED, tol=6)
    assert side > 500, "no side view of the buildings"


def test_exploration_map_fills_in(tmp_path):
    rec = _run("recurrent_demo", tmp_path, 60)
    a = animate(rec, tmp_path / "r.gif", stride=4, progress=False)
    frames = _frames(a.path)
    plots = [f[:, : int(0.7 * f.shape[1])] for f in frames]  # not the legend
    unknown = [_count(f, style.UNKNOWN, tol=4) for f in plots]
    assert unknown[0] > unknown[-1] > 0, unknown
    # the base station stays on top of the map as it fills in
    assert all(_count(f, style.BASE_STATION) > 20 for f in plots), "no base station"


def test_cli_animate_and_run_shortcuts(tmp_path):
    def tether(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run(
            [sys.executable, "-m", "tether.cli", *args],
            cwd=tmp_path,
            capture_output=True,
            text=True,
            timeout=600,
        )

    proc = tether(
        "run",
        "silent_demo",
        "--set",
        "sim.max_steps=15",
        "--out",
        "r",
        "--no-figures",
        "--animate",
        "--view",
    )
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "r" / "animation.gif").stat().st_size > 10_000
    assert (tmp_path / "r" / "replay.html").stat().st_size > 100_000
    assert "animation:" in proc.stdout and "replay:" in proc.stdout
    proc = tether("animate", "r", "--stride", "5", "--out", "x.gif", "--width", "400")
    assert proc.returncode == 0, proc.stderr
    im = Image.open(tmp_path / "x.gif")
    assert im.size[0] == 400 and im.n_frames == 4  # steps 0, 5, 10, 15
    proc = tether("animate", "nowhere")
    assert proc.returncode == 2 and "not a run folder" in proc.stderr
