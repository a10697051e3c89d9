"""The tutorials' files and commands work as written.

The map tutorial's image script and scenario run as printed on the page, and the team
explores the drawn floor: the oracle is the picture itself (every recorded robot
position lies on a free pixel of it). The scene and strategy tutorials include their
files whole from ``examples/`` (run by ``tests/test_examples.py``).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
from PIL import Image

from _cli import tether

ROOT = Path(__file__).resolve().parents[1]
TUTORIALS = ROOT / "docs" / "tutorials"


def _block(page: Path, marker: str) -> str:
    """The fenced block right after ``<!-- marker -->`` on ``page``."""
    pattern = rf"<!-- {marker} -->\n```[^\n]*\n(.*?)```"
    return re.search(pattern, page.read_text(), re.DOTALL).group(1)


def test_the_map_tutorial_runs_as_written(tmp_path, monkeypatch, capsys):
    page = TUTORIALS / "own-map.md"
    monkeypatch.chdir(tmp_path)
    exec(compile(_block(page, "own-map-image"), str(page), "exec"), {})
    Path("my_floor.yaml").write_text(_block(page, "own-map-scenario"))
    assert tether(capsys, "validate", "my_floor.yaml")[0] == 0
    code, out, err = tether(capsys, "run", "my_floor.yaml", "--out", "runs/floor")
    assert code == 0, err
    summary = json.loads(Path("runs/floor/summary.json").read_text())
    assert summary["final_explored_fraction"] > 0.5  # both rooms: through the door
    assert Path("runs/floor/figures/map.png").is_file()
    free = np.asarray(Image.open("my_floor.png")) > 128  # rows from the top, as the page says
    robots = pq.read_table("runs/floor/robots.parquet").to_pydict()
    col = np.floor(np.asarray(robots["x_m"]) / 0.1).astype(int)
    row = free.shape[0] - 1 - np.floor(np.asarray(robots["y_m"]) / 0.1).astype(int)
    assert free[row, col].all(), "a robot stood on a wall of the drawn floor"


def test_the_scene_and_strategy_tutorials_include_the_examples():
    for page, files in {
        "own-3d-scene.md": ["examples/pillars_scene.py", "examples/pillar_hall.yaml"],
        "own-strategy.md": ["examples/custom_strategy.py", "examples/centroid_pull.yaml"],
    }.items():
        text = (TUTORIALS / page).read_text()
        for name in files:
            assert f'--8<-- "{name}"' in text and (ROOT / name).is_file(), (page, name)
