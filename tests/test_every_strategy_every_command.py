"""Every strategy through every command, as a user types them (in the style of VMAS's tests).

For each strategy in the registry (so a new one is covered as soon as it is registered,
and must come with a built-in scenario) and for the example plug-in
``examples/custom_strategy.py``, a short run goes through

``tether run --animate --view``, ``tether animate``, ``tether view`` (the page opened in
headless Chromium), ``tether export --format mcap`` and ``--format rosbag2`` (read back
with the mcap and rosbags readers) and ``tether sweep`` + ``tether report``.

The oracle of every viewer is the run folder itself: positions from ``robots.parquet``,
targets from the run's events (:mod:`tether.targets_recorded`).
"""

from __future__ import annotations

import importlib.util
from collections import defaultdict
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.parquet as pq
import pytest
import yaml
from PIL import Image

from _cli import tether
from conftest import SHARED_MAPS
from test_replay_browser import Page, browser  # noqa: F401  (the Chromium fixture)
from tether import cli
from tether.config import builtin_scenarios, load_scenario
from tether.plugins import load_builtins
from tether.registry import STRATEGIES
from tether.targets_recorded import HIDDEN
from tether.viewing.runfolder import load_run

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "custom_strategy.py"
PLUGIN = "centroid_pull (examples/custom_strategy.py)"
#: steps of every run: a few recorded frames even where positions are kept every 5 steps
STEPS = 10

load_builtins()
CASES = [*STRATEGIES.names(), PLUGIN]


def _builtin_for(strategy: str) -> tuple[str, list[str]]:
    """The first built-in scenario of ``strategy`` and the overrides it needs here."""
    names = [s for s in builtin_scenarios() if load_scenario(s).strategy.name == strategy]
    assert names, f"strategy {strategy!r} has no built-in scenario: add one to src/tether/scenarios"
    name = names[0]
    sc = load_scenario(name)
    path = sc.world.params.get("path")
    if path and not sc.resolve_path(path).exists():  # a map on the shared test data
        shared = SHARED_MAPS / Path(path).name
        if not shared.exists():
            pytest.skip(f"{name}: {path} not found (the shared maps sit beside the repository)")
        return name, [f"world.params.path={shared}"]
    return name, []


def _scenario(case: str, folder: Path) -> tuple[str, list[str]]:
    """What to pass to `tether run` / `tether sweep` for ``case``: scenario and --set's."""
    if case != PLUGIN:
        name, extra = _builtin_for(case)
    else:  # the plug-in registers itself when imported (as `--plugin` or an entry point does)
        spec = importlib.util.spec_from_file_location("tether_example_custom_strategy", EXAMPLE)
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
        name = str(folder / "rendezvous.yaml")
        Path(name).write_text(yaml.safe_dump(module.SCENARIO))
        extra = []
    sets = [*extra, f"sim.max_steps={STEPS}"]
    return name, [a for s in sets for a in ("--set", s)]


def _main(*args: str) -> int:
    try:
        cli.main(list(args))
    except SystemExit as exc:
        return 0 if exc.code is None else exc.code if isinstance(exc.code, int) else 1
    return 0


@pytest.fixture(scope="module", params=CASES)
def case(request, tmp_path_factory) -> dict[str, Any]:
    """One run per case with ``tether run --animate --view``."""
    folder = tmp_path_factory.mktemp(request.param.split()[0])
    scenario, sets = _scenario(request.param, folder)
    run_dir = folder / "run"
    code = _main("run", scenario, "--out", str(run_dir), "--animate", "--view", *sets)
    return {"name": request.param, "scenario": scenario, "sets": sets, "run": run_dir,
            "code": code, "folder": folder}  # fmt: skip


def _recorded(run_dir: Path) -> tuple[np.ndarray, np.ndarray]:
    """Recorded steps and positions ``(T, n, 3)`` from robots.parquet (z = 0 in 2-D)."""
    t = pq.read_table(run_dir / "robots.parquet").to_pydict()
    steps = np.unique(t["step"])
    n = max(t["robot"]) + 1
    pos = np.zeros((len(steps), n, 3))
    idx = np.searchsorted(steps, t["step"])
    for d, col in enumerate(("x_m", "y_m", "z_m")):
        if col in t:
            pos[idx, t["robot"], d] = t[col]
    return steps, pos


def test_run_animate_view(case) -> None:
    assert case["code"] == 0, f"{case['name']}: tether run --animate --view exited {case['code']}"
    run_dir = case["run"]
    for name in ("summary.json", "animation.gif", "replay.html", "figures/snapshot.png"):
        assert (run_dir / name).stat().st_size > 0, name


def test_animate(case, capsys) -> None:
    gif = case["folder"] / "short.gif"
    code, out, err = tether(capsys, "animate", str(case["run"]), "--out", str(gif),
                            "--fps", "4", "--duration", "1")  # fmt: skip
    assert code == 0, err
    steps, _ = _recorded(case["run"])
    with Image.open(gif) as im:
        frames = im.n_frames
    assert frames == min(len(steps), 4) or frames == min(len(steps), 5)  # + the last step
    assert f"{frames} frames" in out


def test_view_in_chromium(case, capsys, browser) -> None:  # noqa: F811
    html = case["folder"] / "view.html"
    code, _, err = tether(capsys, "view", str(case["run"]), "--out", str(html))
    assert code == 0, err
    steps, pos = _recorded(case["run"])
    data = load_run(case["run"], world=False)
    shown = slice(0, data.dim)  # 2-D robots are drawn resting on the ground, z = their radius
    page = Page(browser, html)
    try:
        assert page.js("window.tether.nFrames") == len(steps)
        np.testing.assert_allclose(page.markers()[:, shown], pos[0, :, shown], atol=0.01)
        page.page.fill("#slider", str(len(steps) - 1))
        np.testing.assert_allclose(page.markers()[:, shown], pos[-1, :, shown], atol=0.01)
        if data.targets is not None:  # targets as the run recorded them, at the last frame
            want = data.targets.states(int(data.frame_steps[-1]), float(data.frame_times_s[-1]))
            assert page.js("window.tether.targetStates()") == want.tolist()
            assert np.any(want != HIDDEN)
        assert page.requests == [page.url]
        assert page.errors == []
    finally:
        page.close()


def _read_mcap(path: Path) -> dict[str, list]:
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    out: dict[str, list] = defaultdict(list)
    with open(path, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        for _, channel, _, msg in reader.iter_decoded_messages():
            out[channel.topic].append(msg)
    return out


def _read_rosbag2(path: Path) -> dict[str, list]:
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    out: dict[str, list] = defaultdict(list)
    with Reader(path) as reader:
        for conn, _, raw in reader.messages():
            out[conn.topic].append(ts.deserialize_cdr(raw, conn.msgtype))
    return out


@pytest.mark.parametrize("fmt", ["mcap", "rosbag2"])
def test_export(case, capsys, fmt) -> None:
    out_path = case["folder"] / ("run.mcap" if fmt == "mcap" else "bag")
    code, _, err = tether(capsys, "export", str(case["run"]), "--format", fmt,
                          "--out", str(out_path))  # fmt: skip
    assert code == 0, err
    msgs = _read_mcap(out_path) if fmt == "mcap" else _read_rosbag2(out_path)
    steps, pos = _recorded(case["run"])
    poses = msgs["/tether/robots"]
    assert len(poses) == len(steps)
    for k in (0, len(steps) - 1):
        got = [[p.position.x, p.position.y, p.position.z] for p in poses[k].poses]
        np.testing.assert_allclose(got, pos[k])
    data = load_run(case["run"], world=False)
    if data.targets_m is not None:
        (plan,) = msgs["/tether/plan"]
        (marker,) = [m for m in plan.markers if m.ns == "targets"]
        assert len(marker.points) == len(data.targets_m)


def test_sweep_and_report(case, capsys) -> None:
    sweep_dir = case["folder"] / "sweep"
    code, out, err = tether(capsys, "sweep", case["scenario"], *case["sets"],
                            "--set", "output.figures=false", "--seeds", "2",
                            "--executor", "serial", "--out", str(sweep_dir))  # fmt: skip
    assert code == 0, err
    table = pq.read_table(sweep_dir / "sweep.parquet").to_pydict()
    assert len(table["status"]) >= 2 and set(table["status"]) == {"done"}
    code, out, err = tether(capsys, "report", str(sweep_dir))
    assert code == 0, err
    report = (sweep_dir / "report.md").read_text()
    assert "(2 done, 0 failed)" in report
    for metric in ("connected_all_steps", "collisions", "min_links"):  # varying or constant
        assert f"| {metric} |" in report or f"### {metric}" in report, metric
