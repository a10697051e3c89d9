"""Every output read back by an independent decoder and compared with the run folder.

MCAP through mcap-ros2-support's decoder (it parses the message definitions embedded
in the file), rosbag2 through rosbags' reader, the replay page by unpacking its base64
and gzip buffer as the page's script does. The oracle is always the run folder's
Parquet tables (robots, links, steps) and the map: positions frame by frame (x and y
in their places), links, metric messages stamped at their own step, and the known map
of an exploration run at the frame it was seen (not a frame late, not early).
"""

from __future__ import annotations

import base64
import gzip
import json
import re
from collections import defaultdict
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
import yaml

from _parameter_runs import SILENT, changed
from tether.config import load_scenario, scenario_from_dict
from tether.export.ros2 import export
from tether.runner import build_world, run
from tether.viewing.replay import write_replay


@pytest.fixture(scope="module")
def silent_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A 2-D run whose team heads along x far more than y (swapped axes show)."""
    data = changed(SILENT, sim__dt_s=0.5, sim__max_steps=16, output__record_every=2)
    data["strategy"]["params"]["trajectory"]["waypoints"] = [[0, 0], [40, 6]]
    return run(data, out_dir=tmp_path_factory.mktemp("silent") / "run").path


@pytest.fixture(scope="module")
def explore_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    sc = load_scenario("recurrent_demo")
    sc.sim.max_steps, sc.team.n_robots, sc.output.record_every = 24, 4, 2
    sc.output.figures = False
    return run(sc, out_dir=tmp_path_factory.mktemp("explore") / "run").path


def table(run_dir: Path, name: str) -> dict[str, np.ndarray]:
    return {k: np.asarray(v) for k, v in pq.read_table(run_dir / name).to_pydict().items()}


def recorded(run_dir: Path) -> tuple[np.ndarray, np.ndarray]:
    """Recorded steps and positions ``(T, n, 3)`` from robots.parquet."""
    t = table(run_dir, "robots.parquet")
    steps = np.unique(t["step"])
    pos = np.zeros((len(steps), int(t["robot"].max()) + 1, 3))
    k = np.searchsorted(steps, t["step"])
    for d, col in enumerate(("x_m", "y_m", "z_m")):
        if col in t:
            pos[k, t["robot"], d] = t[col]
    return steps, pos


def links_at(run_dir: Path, step: int) -> set[tuple[int, int]]:
    t = table(run_dir, "links.parquet")
    sel = t["step"] == step
    return {(int(i), int(j)) for i, j in zip(t["i"][sel], t["j"][sel], strict=True)}


def step_time_ns(run_dir: Path) -> dict[int, int]:
    s = table(run_dir, "steps.parquet")
    return {int(k): round(float(t) * 1e9) for k, t in zip(s["step"], s["t_s"], strict=True)}


def read_mcap(path: Path) -> dict[str, list]:
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    out: dict[str, list] = defaultdict(list)
    with open(path, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        for _, channel, message, msg in reader.iter_decoded_messages():
            out[channel.topic].append((message.log_time, msg))
    return out


def read_rosbag2(path: Path) -> dict[str, list]:
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    out: dict[str, list] = defaultdict(list)
    with Reader(path) as reader:
        for conn, t_ns, raw in reader.messages():
            out[conn.topic].append((t_ns, ts.deserialize_cdr(raw, conn.msgtype)))
    return out


def xyz(points: list) -> np.ndarray:
    return np.array([[p.x, p.y, p.z] for p in points]).reshape(-1, 3)


@pytest.mark.parametrize("fmt", ["mcap", "rosbag2"])
def test_markers_and_metrics_decode_to_the_run_folder(silent_run: Path, tmp_path: Path, fmt: str):
    result = export(silent_run, tmp_path / ("out.mcap" if fmt == "mcap" else "bag"), fmt=fmt)
    msgs = (read_mcap if fmt == "mcap" else read_rosbag2)(result.path)
    steps, pos = recorded(silent_run)
    t_ns = step_time_ns(silent_run)
    assert np.abs(pos[..., 0] - pos[..., 1]).min() > 0.01  # x and y are told apart
    spheres, lines = msgs["/tether/robot_markers"], msgs["/tether/links"]
    assert len(spheres) == len(lines) == len(steps) == 9
    for k, step in enumerate(steps):
        log_ns, array = spheres[k]
        (marker,) = array.markers
        assert log_ns == t_ns[step]
        np.testing.assert_array_equal(xyz(marker.points), pos[k])  # robot order, x, y, z
        (line,) = lines[k][1].markers
        ends = xyz(line.points).reshape(-1, 2, 3)
        want = {tuple(np.r_[pos[k, i], pos[k, j]]) for i, j in links_at(silent_run, step)}
        assert {tuple(np.r_[a, b]) for a, b in ends} == want and len(ends) == len(want)
    s = table(silent_run, "steps.parquet")
    for col in ("lambda2", "n_links", "min_distance_m", "connected", "collisions"):
        got = msgs[f"/tether/metrics/{col}"]
        want = [(t_ns[int(k)], float(v)) for k, v in zip(s["step"], s[col], strict=True)]
        assert [(ns, m.data) for ns, m in got] == want, col  # each at its own step's time


def payload(html: str) -> tuple[dict, dict[str, np.ndarray]]:
    """The page's embedded run, unpacked as its script does."""
    meta = json.loads(re.search(r'id="tether-meta">(.*?)</script>', html, re.S).group(1))
    blob = re.search(r'id="tether-data">(.*?)</script>', html, re.S).group(1).strip()
    raw = gzip.decompress(base64.b64decode(blob))
    arrays = {
        a["name"]: np.frombuffer(raw, np.dtype(a["dtype"]), a["length"], a["offset"]).reshape(
            a["shape"]
        )
        for a in meta["arrays"]
    }
    return meta, arrays


def positions(meta: dict, arrays: dict) -> np.ndarray:
    """(F, n, 3) metres from the uint16 frame differences (wrapping, as in JavaScript)."""
    q = np.cumsum(arrays["pos"].astype(np.uint64), axis=2) % 65536
    lo, scale = np.asarray(meta["quant"]["lo"]), np.asarray(meta["quant"]["scale"])
    return (lo[:, None, None] + q * scale[:, None, None]).transpose(2, 1, 0)


def test_replay_frames_are_the_run_folder_frames(explore_run: Path, tmp_path: Path):
    meta, arrays = payload(write_replay(explore_run, tmp_path / "r.html").path.read_text())
    steps, pos = recorded(explore_run)
    assert list(arrays["frame_steps"]) == list(steps) and meta["stride"] == 1
    np.testing.assert_allclose(positions(meta, arrays), pos, atol=0.002)
    off, ij = arrays["link_off"], arrays["link_ij"].reshape(-1, 2)
    for k, step in enumerate(steps):
        assert {tuple(map(int, p)) for p in ij[off[k] : off[k + 1]]} == links_at(explore_run, step)


def grid_of(run_dir: Path):  # noqa: ANN201
    sc = scenario_from_dict(yaml.safe_load((run_dir / "scenario.yaml").read_text()))
    return build_world(sc, np.random.default_rng(sc.seed)).grid, sc.sensing.range_m


def test_replay_known_map_appears_at_the_frame_it_is_seen(explore_run: Path, tmp_path: Path):
    """At frame k the cells under the robots are known, and nothing farther than the
    sensing range from every position up to frame k is (a map a frame late has nothing
    at frame 0; one a frame early shows cells seen only from the next positions)."""
    meta, arrays = payload(write_replay(explore_run, tmp_path / "r.html").path.read_text())
    grid, range_m = grid_of(explore_run)
    world = meta["world"]
    assert world["kind"] == "map" and world["cell_m"] == grid.resolution_m
    assert (world["nx"], world["ny"]) == grid.occupied.shape
    np.testing.assert_array_equal(arrays["map_occupied"].T == 1, grid.occupied)  # rows along y
    first = arrays["map_first_seen"].T  # (nx, ny), frame index (uint32 max: never)
    assert first.shape == grid.occupied.shape
    _, pos = recorded(explore_run)
    centres = grid.origin_m + (np.argwhere(np.ones(first.shape)) + 0.5) * grid.resolution_m
    for k in range(len(pos)):
        known = (first <= k).ravel()
        own = np.floor((pos[k, :, :2] - grid.origin_m) / grid.resolution_m).astype(int)
        assert (first[own[:, 0], own[:, 1]] <= k).all(), f"frame {k}: robot cells unknown"
        past = pos[: k + 1, :, :2].reshape(-1, 2)
        near = np.zeros(len(centres), dtype=bool)
        for p in past:
            near |= np.linalg.norm(centres - p, axis=1) <= range_m + grid.resolution_m
        assert not (known & ~near).any(), f"frame {k}: cells known beyond every robot's range"
    assert (first == 0).sum() > 100  # frame 0 shows what the start saw


def test_exported_known_map_appears_at_the_frame_it_is_seen(explore_run: Path, tmp_path: Path):
    msgs = read_mcap(export(explore_run, tmp_path / "e.mcap", fmt="mcap").path)
    grid, _ = grid_of(explore_run)
    steps, pos = recorded(explore_run)
    t_ns = step_time_ns(explore_run)
    frame_of = {t_ns[int(s)]: k for k, s in enumerate(steps)}
    known = msgs["/tether/known_map"]
    assert len(known) >= 2 and frame_of[known[0][0]] == 0
    for log_ns, m in known:
        k = frame_of[log_ns]
        cells = np.asarray(m.data).reshape(m.info.height, m.info.width).T  # (nx, ny)
        own = np.floor((pos[k, :, :2] - grid.origin_m) / grid.resolution_m).astype(int)
        assert (cells[own[:, 0], own[:, 1]] != -1).all(), f"frame {k}: robot cells unknown"
        np.testing.assert_array_equal(cells[cells != -1] == 100, grid.occupied[cells != -1])
