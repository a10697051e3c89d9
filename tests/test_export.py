"""ROS 2 export read back with independent readers: one pose message per recorded step,
at the recorded positions and simulation times (MCAP via mcap-ros2-support's decoder,
which parses the embedded message definitions; rosbag2 via rosbags' reader)."""

from __future__ import annotations

import subprocess
import sys
from collections import defaultdict
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
import yaml

from tether.config import load_scenario
from tether.errors import TetherError
from tether.export.ros2 import export
from tether.runner import run
from tether.viewing.runfolder import load_run
from tether.viz.boxes import obstacle_boxes


def _run(name: str, tmp_path: Path, steps: int) -> Path:
    sc = load_scenario(name)
    sc.sim.max_steps = steps
    sc.output.figures = False
    return run(sc, out_dir=tmp_path / name).path


@pytest.fixture(scope="module")
def town(tmp_path_factory) -> Path:
    return _run("connectivity_town", tmp_path_factory.mktemp("town"), 25)


def _recorded(run_dir: Path) -> tuple[np.ndarray, np.ndarray]:
    t = pq.read_table(run_dir / "robots.parquet").to_pydict()
    steps = np.unique(t["step"])
    cols = ["x_m", "y_m", "z_m"] if "z_m" in t else ["x_m", "y_m"]
    n = max(t["robot"]) + 1
    pos = np.zeros((len(steps), n, 3))
    idx = np.searchsorted(steps, t["step"])
    for d, c in enumerate(cols):
        pos[idx, t["robot"], d] = t[c]
    return steps, pos


def _read_mcap(path: Path) -> dict[str, list]:
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    out: dict[str, list] = defaultdict(list)
    with open(path, "rb") as fh:
        reader = make_reader(fh, decoder_factories=[DecoderFactory()])
        for schema, channel, message, msg in reader.iter_decoded_messages():
            out[channel.topic].append((message.log_time, msg, schema.name))
    return out


def _read_rosbag2(path: Path) -> dict[str, list]:
    from rosbags.rosbag2 import Reader
    from rosbags.typesys import Stores, get_typestore

    ts = get_typestore(Stores.ROS2_HUMBLE)
    out: dict[str, list] = defaultdict(list)
    with Reader(path) as reader:
        for conn, t_ns, raw in reader.messages():
            out[conn.topic].append((t_ns, ts.deserialize_cdr(raw, conn.msgtype), conn.msgtype))
    return out


def _stamp_ns(msg) -> int:
    return msg.header.stamp.sec * 10**9 + msg.header.stamp.nanosec


def test_mcap_has_one_pose_array_per_recorded_step_at_the_recorded_positions(town, tmp_path):
    result = export(town, tmp_path / "town.mcap", fmt="mcap")
    msgs = _read_mcap(result.path)
    steps, pos = _recorded(town)
    t_s = pq.read_table(town / "steps.parquet").to_pydict()
    t_of = dict(zip(t_s["step"], t_s["t_s"], strict=True))  # dt = 0.1 s: time != step
    poses = msgs["/tether/robots"]
    assert len(poses) == len(steps) == 26
    for k, (log_ns, msg, schema) in enumerate(poses):
        assert schema == "geometry_msgs/msg/PoseArray"
        assert msg.header.frame_id == "map"
        assert log_ns == _stamp_ns(msg) == round(t_of[steps[k]] * 1e9)
        got = np.array([[p.position.x, p.position.y, p.position.z] for p in msg.poses])
        np.testing.assert_array_equal(got, pos[k])
        assert all(p.orientation.w == 1.0 for p in msg.poses)
    # links: one line list per recorded step, two points per recorded link
    link_steps = np.asarray(pq.read_table(town / "links.parquet")["step"])
    lines = msgs["/tether/links"]
    assert len(lines) == len(steps)
    for k, (_, msg, _) in enumerate(lines):
        (marker,) = msg.markers
        assert marker.type == 5 and len(marker.points) == 2 * np.sum(link_steps == steps[k])
        assert len(marker.colors) == len(marker.points)
    # the town's buildings as boxes, once
    (obstacles,) = msgs["/tether/obstacles"]
    assert len(obstacles[1].markers) == len(obstacle_boxes(load_run(town).grid)) > 10
    # per-step metrics as Float64
    lam = msgs["/tether/metrics/lambda2"]
    np.testing.assert_allclose([m.data for _, m, _ in lam], t_s["lambda2"])
    assert result.messages["/tether/robots"] == 26


def test_rosbag2_exploration_run_poses_map_and_base_station(tmp_path):
    run_dir = _run("recurrent_demo", tmp_path, 40)  # positions recorded every 5 steps
    result = export(run_dir, tmp_path / "bag", fmt="rosbag2")
    meta = yaml.safe_load((result.path / "metadata.yaml").read_text())
    assert meta["rosbag2_bagfile_information"]["storage_identifier"] == "sqlite3"
    msgs = _read_rosbag2(result.path)
    steps, pos = _recorded(run_dir)
    assert list(steps) == list(range(0, 41, 5))
    poses = msgs["/tether/robots"]
    assert len(poses) == len(steps)
    for k, (t_ns, msg, _) in enumerate(poses):
        assert t_ns == _stamp_ns(msg) == steps[k] * 10**9  # dt = 1 s
        got = np.array([[p.position.x, p.position.y, p.position.z] for p in msg.poses])
        np.testing.assert_array_equal(got, pos[k])
    (grid_msg,) = [m for _, m, _ in msgs["/map"]]
    grid = load_run(run_dir).grid
    assert (grid_msg.info.width, grid_msg.info.height) == grid.occupied.shape
    assert grid_msg.info.resolution == pytest.approx(grid.resolution_m)
    data = np.asarray(grid_msg.data).reshape(grid_msg.info.height, grid_msg.info.width)
    np.testing.assert_array_equal(data.T == 100, grid.occupied)  # row-major, x fastest
    (plan,) = [m for _, m, _ in msgs["/tether/plan"]]
    (bs,) = [mk for mk in plan.markers if mk.ns == "base_station"]
    base = load_run(run_dir).base_m
    assert (bs.pose.position.x, bs.pose.position.y) == pytest.approx(tuple(base))
    known = msgs["/tether/known_map"]
    unknown = [int(np.sum(np.asarray(m.data) == -1)) for _, m, _ in known]
    assert len(known) >= 2 and unknown == sorted(unknown, reverse=True) and unknown[-1] < unknown[0]


def test_cli_export_and_bad_format(town, tmp_path):
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "tether.cli",
            "export",
            str(town),
            "--format",
            "rosbag2",
            "--out",
            str(tmp_path / "b"),
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 0, proc.stderr
    assert "rosbag2" in proc.stdout and (tmp_path / "b" / "metadata.yaml").exists()
    assert len(_read_rosbag2(tmp_path / "b")["/tether/robots"]) == 26
    proc = subprocess.run(
        [sys.executable, "-m", "tether.cli", "export", str(town), "--format", "bag"],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 2 and "expected one of mcap, rosbag2" in proc.stderr
    with pytest.raises(TetherError, match="already exists"):
        export(town, tmp_path / "b", fmt="rosbag2")


def test_fast_marker_encoding_is_byte_identical_to_rosbags(town, tmp_path):
    """The NumPy CDR path for links and robot markers against rosbags' own serializer."""
    from tether.export.ros2 import FRAME_ID, Messages

    msgs = Messages(load_run(town))
    for k in (0, 7, 25):
        t = float(msgs.run.frame_times_s[k])
        for name, points, fast, mtype, scale in (
            ("links", msgs.link_points, msgs.links, 5, 0.25 * msgs.rad),
            ("robots", msgs.robot_points, msgs.robot_markers, 7, 2 * msgs.rad),
        ):
            pts, cols = points(k)
            assert len(pts) > 0
            slow = msgs.marker_array(
                [
                    msgs.marker(
                        t,
                        name,
                        mtype,
                        points=[msgs.point(p) for p in pts],
                        colours=[msgs.colour(c) for c in cols],
                        scale=scale,
                    )
                ]
            )
            assert fast(k, t) == slow, (name, k)
    assert msgs.header(0.0).frame_id == FRAME_ID
    # and with no links at all (an empty sequence needs no alignment padding)
    msgs.run.link_offsets[:] = 0
    slow = msgs.marker_array([msgs.marker(0.0, "links", 5, scale=0.25 * msgs.rad)])
    assert msgs.links(0, 0.0) == slow
