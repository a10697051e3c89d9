"""Recurrent scenario values within their fields' bounds that a run cannot use.

Each is refused by ``tether validate`` and ``tether run`` alike with one line
(exit code 2) naming the field and the fix, and the value the message offers
instead does run.
"""

from __future__ import annotations

import re
import time
from pathlib import Path

import numpy as np
import pytest

from _cli import tether
from tether.config import load_scenario
from tether.recurrent.exploration.sim import ExplorationConfig, ExplorationSim, GoalKind

ROOT = Path(__file__).resolve().parents[1]


def _refused(capsys: pytest.CaptureFixture[str], *args: str) -> str:
    """The single error line of ``tether ARGS``, asserting exit code 2."""
    code, _, err = tether(capsys, *args)
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err and "internal error" not in err
    return lines[0]


def _runs(capsys: pytest.CaptureFixture[str], tmp_path: Path, name: str, *sets: str) -> None:
    """``tether validate`` and a 3-step ``tether run`` both succeed."""
    args = [a for s in sets for a in ("--set", s)]
    code, _, err = tether(capsys, "validate", name, *args)
    assert code == 0, err
    out = str(tmp_path / "run")
    run = ("run", name, *args, "--set", "sim.max_steps=3", "--no-figures", "--out", out)
    code, _, err = tether(capsys, *run)
    assert code == 0, err


def _least(line: str) -> str:
    found = re.search(r"at least (\S+) m", line)
    assert found, line
    return found.group(1)


def test_sensing_range_short_of_the_bs_coarse_cell(capsys, tmp_path):
    """0.05 m (half a 0.1 m cell) died in the planner; the stated minimum runs."""
    for cmd in ("validate", "run"):
        line = _refused(capsys, cmd, "recurrent_demo", "--set", "sensing.range_m=0.05")
        assert "sensing.range_m" in line and "0.1 m" in line and "coarse" in line
    assert _least(line) == "0.1"
    # samples are every half cell: 0.09 m (0.9 cells) sees no more than 0.05 m
    _refused(capsys, "validate", "recurrent_demo", "--set", "sensing.range_m=0.09")
    _runs(capsys, tmp_path, "recurrent_demo", "sensing.range_m=0.1")


def test_sensing_range_minimum_grows_with_the_coarse_cell(capsys, tmp_path):
    sets = ("strategy.params.coarse_cell_m=0.5", "sensing.range_m=0.1")
    line = _refused(capsys, "validate", "recurrent_demo", *[a for s in sets for a in ("--set", s)])
    least = _least(line)
    assert float(least) > 0.1
    _runs(capsys, tmp_path, "recurrent_demo", sets[0], f"sensing.range_m={least}")


def test_utility_needs_no_known_bs_cell(capsys, tmp_path, monkeypatch):
    """The check is the recurrent planner's only: the baseline runs with a short range."""
    monkeypatch.chdir(ROOT)  # the scenario's map is ../shared/maps from the checkout
    _runs(capsys, tmp_path, "recurrent_utility", "sensing.range_m=0.05")


def test_speed_rounding_to_zero_cells(capsys, tmp_path):
    for cmd in ("validate", "run"):
        line = _refused(capsys, cmd, "recurrent_demo", "--set", "strategy.params.speed_m_s=1e-300")
        assert "strategy.params.speed_m_s" in line
    least = re.search(r"at least (\S+) m/s", line)
    assert least, line
    _runs(capsys, tmp_path, "recurrent_demo", f"strategy.params.speed_m_s={least.group(1)}")


def test_signal_ref_distance_rounding_to_zero_cells(capsys):
    line = _refused(
        capsys,
        "validate",
        "recurrent_demo",
        "--set",
        "strategy.params.link_model=signal",
        "--set",
        "strategy.params.signal.ref_distance_m=1e-300",
    )
    assert "strategy.params.signal.ref_distance_m" in line


def test_coarse_cell_wider_than_the_map_is_refused_at_once(capsys, tmp_path):
    start = time.perf_counter()
    line = _refused(
        capsys, "validate", "recurrent_demo", "--set", "strategy.params.coarse_cell_m=1e7"
    )
    assert time.perf_counter() - start < 5.0
    assert "strategy.params.coarse_cell_m" in line and "wider than the map" in line


def test_tiny_resolution_is_refused_at_once(capsys, monkeypatch, skip_without_shared_map):
    monkeypatch.chdir(ROOT)  # the scenario's map is ../shared/maps from the checkout
    skip_without_shared_map(load_scenario("recurrent_grass"))
    for res in ("1.0e-300", "1.0e-320"):
        start = time.perf_counter()
        line = _refused(
            capsys, "validate", "recurrent_grass", "--set", f"world.params.resolution_m={res}"
        )
        assert time.perf_counter() - start < 5.0
        assert "world.params.resolution_m" in line


@pytest.mark.parametrize("value", ["", "123", "[a]", '""'])
def test_map_path_must_be_a_string(capsys, value):
    line = _refused(capsys, "validate", "recurrent_grass", "--set", f"world.params.path={value}")
    assert "world.params.path" in line and "file path string" in line


def test_least_speed_offered_moves_a_robot(capsys):
    """The speed the message offers advances a robot in the simulator (not only runs)."""
    line = _refused(
        capsys, "validate", "recurrent_demo", "--set", "strategy.params.speed_m_s=1e-300"
    )
    least_m_s = float(re.search(r"at least (\S+) m/s", line).group(1))
    scenario = load_scenario("recurrent_demo")
    resolution_m = 0.1  # the demo's map
    speed_cells = round(least_m_s * scenario.sim.dt_s / resolution_m, 9)
    cfg = ExplorationConfig(n_robots=1, speed_cells=speed_cells, coarse_factor=3)
    sim = ExplorationSim(np.zeros((30, 30), bool), np.array([15.0, 15.0]), None, cfg)
    start = sim.pos[0].copy()
    goal = start + [5.0, 0.0]
    sim.assign(0, goal, GoalKind.FRONTIER, goal[None])
    sim.t = 1
    sim._move()
    assert sim.pos[0][0] > start[0]


def test_tiny_resolution_of_a_procedural_scene_is_one_line(capsys):
    """The cell count overflows to inf: refused without numpy's overflow warnings."""
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("error")  # a RuntimeWarning would print a second line
        line = _refused(
            capsys, "validate", "recurrent_demo", "--set", "world.params.resolution_m=1.0e-300"
        )
    assert "resolution_m" in line and "cells" in line
