"""A run folder keeps the files its world read, so it runs again from any folder.

The map (a PNG, or a ROS map YAML with its image) is copied into ``RUN/files/``, the
run's ``scenario.yaml`` points at the copy and ``summary.json`` records its SHA-256;
``tether run RUN/scenario.yaml`` from another folder, after the original is gone,
gives the same run.
"""

from __future__ import annotations

import hashlib
import json
import shutil
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import yaml
from PIL import Image

from _cli import tether
from tether import scenario_world

SCENARIO = """
name: kept
world: {{scene: map, dim: 2, params: {{path: {path}, resolution_m: 0.5}}}}
team:
  n_robots: 4
  init: {{kind: random_connected, spacing_m: 3.0, center: [5.0, 5.0]}}
sensing: {{range_m: 6.0}}
sim: {{dt_s: 1.0, max_steps: 15}}
strategy:
  name: silent
  params: {{d0_m: 3.0, trajectory: {{kind: waypoints, waypoints: [[5, 5], [25, 5]],
           speed_mps: 1.0}}}}
output: {{figures: false}}
"""


def _room(path: Path) -> None:
    img = np.full((40, 60), 255, np.uint8)
    img[[0, -1], :] = img[:, [0, -1]] = 0
    img[5:20, 35] = 0  # a wall from y = 10 m up
    Image.fromarray(img).save(path)


def _positions(run: Path) -> np.ndarray:
    robots = pq.read_table(run / "robots.parquet").to_pydict()
    return np.stack([robots["x_m"], robots["y_m"]], axis=1)


def _run_twice(capsys, tmp_path: Path, monkeypatch, map_name: str) -> tuple[Path, Path]:
    work, elsewhere = tmp_path / "work", tmp_path / "elsewhere"
    work.mkdir(exist_ok=True), elsewhere.mkdir()
    (work / "s.yaml").write_text(SCENARIO.format(path=map_name))
    monkeypatch.chdir(work)
    code, _, err = tether(capsys, "run", "s.yaml", "--out", str(tmp_path / "first"))
    assert code == 0, err
    shutil.rmtree(work)  # the original map (and scenario) are gone
    monkeypatch.chdir(elsewhere)
    code, _, err = tether(capsys, "run", str(tmp_path / "first" / "scenario.yaml"),
                          "--out", str(tmp_path / "second"))  # fmt: skip
    assert code == 0, err
    return tmp_path / "first", tmp_path / "second"


def test_a_run_folder_runs_again_from_elsewhere(capsys, tmp_path, monkeypatch):
    (tmp_path / "work").mkdir()
    _room(tmp_path / "work" / "room.png")
    original = hashlib.sha256((tmp_path / "work" / "room.png").read_bytes()).hexdigest()
    first, second = _run_twice(capsys, tmp_path, monkeypatch, "room.png")
    kept = json.loads((first / "summary.json").read_text())["scene_files"]
    assert kept == [{
        "key": "world.params.path", "given": "room.png", "stand_in": None,
        "used": str((tmp_path / "work" / "room.png").resolve()), "sha256": original,
        "bytes": (first / "files" / "room.png").stat().st_size, "copy": "files/room.png",
    }]  # fmt: skip
    assert yaml.safe_load((first / "scenario.yaml").read_text())["world"]["params"]["path"] == (
        "files/room.png"
    )
    np.testing.assert_array_equal(_positions(first), _positions(second))
    again = json.loads((second / "summary.json").read_text())["scene_files"][0]
    assert again["sha256"] == original  # the copy is the original, byte for byte


def test_a_ros_map_keeps_its_image(capsys, tmp_path, monkeypatch):
    (tmp_path / "work" / "maps").mkdir(parents=True)
    _room(tmp_path / "work" / "maps" / "floor.png")
    (tmp_path / "work" / "room.yaml").write_text(
        "image: maps/floor.png\nresolution: 0.5\norigin: [0.0, 0.0, 0.0]\n"
        "negate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n"
    )
    first, second = _run_twice(capsys, tmp_path, monkeypatch, "room.yaml")
    kept = yaml.safe_load((first / "files" / "room.yaml").read_text())
    assert kept["image"] == "floor.png" and (first / "files" / "floor.png").is_file()
    np.testing.assert_array_equal(_positions(first), _positions(second))


def test_a_large_file_is_recorded_by_path_and_hash(capsys, tmp_path, monkeypatch):
    monkeypatch.setattr(scenario_world, "MAX_KEPT_BYTES", 10)
    _room(tmp_path / "room.png")
    (tmp_path / "s.yaml").write_text(SCENARIO.format(path="room.png"))
    monkeypatch.chdir(tmp_path)
    code, _, err = tether(capsys, "run", "s.yaml", "--out", "r")
    assert code == 0, err
    assert not (tmp_path / "r" / "files").exists()
    kept = json.loads((tmp_path / "r" / "summary.json").read_text())["scene_files"][0]
    assert kept["copy"] is None and len(kept["sha256"]) == 64
    path = yaml.safe_load((tmp_path / "r" / "scenario.yaml").read_text())["world"]["params"]
    assert path["path"] == str((tmp_path / "room.png").resolve())
