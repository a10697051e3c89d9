"""The command line: the demo, run folders, and one-line errors for bad input."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
import yaml
from PIL import Image

from tether.config import builtin_scenarios, load_scenario

SUMMARY_KEYS = {
    "scenario",
    "strategy",
    "seed",
    "n_robots",
    "sim_time_s",
    "steps",
    "wall_time_s",
    "connected_all_steps",
    "min_lambda2",
    "min_links",
    "collisions",
}


def tether(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "tether.cli", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=300,
    )


def test_run_without_arguments_runs_the_demo_and_says_where(tmp_path):
    proc = tether("run", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    line = [ln for ln in proc.stdout.splitlines() if ln.startswith("results:")][0]
    run_dir = tmp_path / line.split(":", 1)[1].strip()
    summary = json.loads((run_dir / "summary.json").read_text())
    assert set(summary) >= SUMMARY_KEYS
    assert summary["connected_all_steps"] is True
    steps = pq.read_table(run_dir / "steps.parquet").to_pydict()
    assert len(steps["step"]) == summary["steps"] + 1
    assert min(steps["n_links"]) == summary["min_links"]
    robots = pq.read_table(run_dir / "robots.parquet")
    assert robots.num_rows == (summary["steps"] + 1) * summary["n_robots"]
    assert (run_dir / "events.parquet").exists()
    assert yaml.safe_load((run_dir / "scenario.yaml").read_text())["name"] == "silent_demo"
    assert (run_dir / "figures" / "links.png").stat().st_size > 1000
    assert (run_dir / "figures" / "snapshot.png").stat().st_size > 1000


def _demo() -> dict:
    scenario = load_scenario("silent_demo")
    return yaml.safe_load((scenario.base_dir / "silent_demo.yaml").read_text())


def _write(tmp_path: Path, data: dict, name: str = "bad.yaml") -> Path:
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data))
    return path


def _map_world(tmp_path: Path) -> dict:
    img = np.full((40, 60), 255, dtype=np.uint8)  # rows = y (top first), cols = x
    img[:, 30] = 0  # a vertical wall at x = 30 m
    Image.fromarray(img).save(tmp_path / "wall.png")
    return {"scene": "map", "dim": 2, "params": {"path": "wall.png", "resolution_m": 1.0}}


BAD_CASES = {
    "unknown key": (lambda d, p: d["sensing"].update(rnage_m=3), "sensing.rnage_m"),
    "wrong type": (lambda d, p: d["team"].update(n_robots="many"), "team.n_robots"),
    "negative range": (lambda d, p: d["sensing"].update(range_m=-3), "sensing.range_m"),
    "unknown strategy": (lambda d, p: d["strategy"].update(name="telepathy"), "strategy.name"),
    "bad strategy param": (
        lambda d, p: d["strategy"]["params"].update(gamma=-1),
        "strategy.params.gamma",
    ),
    "missing map": (
        lambda d, p: d.update(world={"scene": "map", "params": {"path": "nope.png"}}),
        "nope.png",
    ),
    "corrupt map": (
        lambda d, p: (
            p.joinpath("corrupt.png").write_bytes(b"not a png"),
            d.update(world={"scene": "map", "params": {"path": "corrupt.png"}}),
        ),
        "corrupt.png",
    ),
    "team not connected": (
        lambda d, p: d["team"]["init"].update(kind="grid", spacing_m=40.0),
        "team.init",
    ),
    "leader path through obstacle": (
        lambda d, p: (
            d.update(world=_map_world(p)),
            d["team"]["init"].update(center=[10.0, 20.0], spacing_m=5.0),
            d["strategy"]["params"]["trajectory"].update(waypoints=[[10, 20], [50, 20]]),
        ),
        "strategy.params.trajectory",
    ),
    "not yaml": (None, "not valid YAML"),
}


@pytest.mark.parametrize("case", sorted(BAD_CASES))
def test_bad_input_is_one_clear_line(tmp_path, case):
    mutate, needle = BAD_CASES[case]
    if mutate is None:
        path = tmp_path / "bad.yaml"
        path.write_text("name: [unclosed\n")
    else:
        data = _demo()
        mutate(data, tmp_path)
        path = _write(tmp_path, data)
    proc = tether("run", str(path), "--out", str(tmp_path / "out"), cwd=tmp_path)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1, proc.stderr
    assert "Traceback" not in proc.stderr
    assert str(path) in lines[0] or "bad.yaml" in lines[0]
    assert needle in lines[0]
    assert not (tmp_path / "out" / "summary.json").exists()


def test_missing_scenario_file_names_the_builtins(tmp_path):
    proc = tether("run", "nowhere.yaml", cwd=tmp_path)
    assert proc.returncode == 2
    assert "nowhere.yaml: file not found" in proc.stderr
    assert "silent_demo" in proc.stderr


def test_set_overrides_and_validate(tmp_path):
    proc = tether("validate", "silent_paper", "--set", "strategy.params.d0_m=5", cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    proc = tether("validate", "silent_paper", "--set", "strategy.params.d0_m=-5", cwd=tmp_path)
    assert proc.returncode == 2 and "strategy.params.d0_m" in proc.stderr


@pytest.mark.parametrize("name", builtin_scenarios())
def test_every_builtin_scenario_validates_and_runs_briefly(tmp_path, name, skip_without_shared_map):
    """Meta-test (as in VMAS): every shipped scenario loads, builds and runs a few steps."""
    from tether.runner import run

    scenario = load_scenario(name)
    skip_without_shared_map(scenario)
    short = scenario.model_copy(update={"sim": scenario.sim.model_copy(update={"max_steps": 5})})
    short._source, short._base_dir = scenario.source, scenario.base_dir
    outcome = run(short, out_dir=tmp_path / name, figures=False)
    assert outcome.summary["steps"] <= 5
    assert (tmp_path / name / "summary.json").exists()
