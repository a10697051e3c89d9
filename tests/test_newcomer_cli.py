"""What a newcomer meets first on the command line: help, version, plain English, notes,
close names suggested for misspelt ones, a complete `tether list`."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
import yaml
from PIL import Image

from _cli import tether
from tether import __version__, cli
from tether.terminal.help import flow, summary

COMMANDS = [c.name or c.callback.__name__.rstrip("_") for c in cli.app.registered_commands]


def _text(output: str) -> str:
    """Help text without rich's boxes and padding, one line per line."""
    lines = [re.sub(r"[│╭╮╰╯─]", " ", line).strip() for line in output.splitlines()]
    return "\n".join(" ".join(line.split()) for line in lines)


def test_bare_tether_and_h_print_help(capsys) -> None:
    for args in ((), ("-h",), ("--help",)):
        code, out, err = tether(capsys, *args)
        assert code == 0 and err == ""
        assert "Usage: tether" in out and all(c in out for c in COMMANDS)
    code, out, _ = tether(capsys, "run", "-h")
    assert code == 0 and "Usage: tether run" in out


def test_version_and_python_m_tether(capsys) -> None:
    code, out, _ = tether(capsys, "--version")
    assert code == 0
    assert re.fullmatch(rf"tether {re.escape(__version__)} \(commit \S+\)\n", out)
    done = subprocess.run([sys.executable, "-m", "tether", "--version"], capture_output=True,
                          text=True, timeout=120)  # fmt: skip
    assert done.returncode == 0 and done.stdout == out


@pytest.mark.parametrize("command", COMMANDS)
def test_help_paragraphs_are_never_broken_mid_sentence(capsys, monkeypatch, command) -> None:
    monkeypatch.setenv("COLUMNS", "400")  # wide enough for any paragraph on one line
    callback = next(c.callback for c in cli.app.registered_commands
                    if (c.name or c.callback.__name__.rstrip("_")) == command)  # fmt: skip
    code, out, _ = tether(capsys, command, "--help")
    assert code == 0
    for paragraph in flow(callback.__doc__).split("\n\n"):
        assert paragraph in _text(out).splitlines(), paragraph
    code, out, _ = tether(capsys, "--help")
    line = next(s for s in _text(out).splitlines() if s.startswith(command + " "))
    assert line == f"{command} {summary(callback.__doc__)}"
    assert line.endswith("."), "a command's summary is a whole sentence"


def test_counts_in_plain_english(capsys) -> None:
    code, out, _ = tether(capsys, "validate", "silent_demo", "--set", "team.n_robots=1")
    assert code == 0 and "(silent, 1 robot)" in out
    code, out, _ = tether(capsys, "validate", "silent_paper")
    assert code == 0 and "20 robots, sweep of 3 combinations)" in out


def test_run_summary_prints_no_missing_values(capsys, tmp_path) -> None:
    code, out, _ = tether(capsys, "run", "connectivity_empty", "--set", "sim.max_steps=3",
                          "--no-figures", "-q", "--out", str(tmp_path / "r"))  # fmt: skip
    assert code == 0
    assert "None" not in out and "min_obstacle_clearance_m" not in out  # free space: none


def _wall_scenario(folder: Path) -> Path:
    """A silent team led around the end of a long wall (2-D map): walls cut links."""
    img = np.full((200, 160), 255, np.uint8)  # 0.5 m cells: 80 m x 100 m
    img[0, :] = img[-1, :] = img[:, 0] = img[:, -1] = 0
    img[25:, 78:82] = 0  # a wall from the bottom up to y = 87.5 m, at x = 39-41 m
    Image.fromarray(img).save(folder / "wall.png")
    data = {
        "name": "silent_wall", "seed": 1,
        "world": {"scene": "map", "dim": 2, "params": {"path": "wall.png", "resolution_m": 0.5}},
        "team": {"n_robots": 10, "init": {"kind": "random_connected", "spacing_m": 6.0,
                                          "min_separation_m": 2.0, "center": [20, 20]}},
        "sensing": {"range_m": 15.0, "radial_error_m": 0.45, "angular_error_deg": 12.0},
        "sim": {"dt_s": 1.0, "max_steps": 400},
        "strategy": {"name": "silent", "params": {"d0_m": 8.0, "trajectory": {
            "waypoints": [[20, 20], [20, 92], [60, 92], [60, 10]], "speed_mps": 1.0}}},
        "output": {"figures": False},
    }  # fmt: skip
    (folder / "wall.yaml").write_text(yaml.safe_dump(data))
    return folder / "wall.yaml"


def test_a_silent_team_cut_by_walls_is_told_so(capsys, tmp_path) -> None:
    scenario = _wall_scenario(tmp_path)
    code, out, _ = tether(capsys, "run", str(scenario), "-q", "--out", str(tmp_path / "r"))
    assert code == 0
    steps = pq.read_table(tmp_path / "r" / "steps.parquet").to_pydict()
    apart = [s for s, ok in zip(steps["step"], steps["connected"], strict=True) if not ok]
    assert apart, "the walls did not cut the team: the test would check nothing"
    notes = [s for s in out.splitlines() if s.startswith("note: ")]
    assert notes[0] == (f"note: the team was disconnected at {len(apart)} of "
                        f"{len(steps['step'])} steps (first at step {apart[0]})")  # fmt: skip
    assert "Theorem 1" in notes[1] and "free space" in notes[1]
    code, out, _ = tether(capsys, "run", "silent_demo", "-q", "--no-figures",
                          "--out", str(tmp_path / "free"))  # fmt: skip
    assert code == 0 and "note:" not in out  # connected at every step: nothing to say


@pytest.mark.parametrize(
    ("args", "hint"),
    [
        (("--set", "strategy.params.gama=0.3"), "(did you mean 'gamma'?)"),
        (("--set", "sim.max_step=3"), "(did you mean 'max_steps'?)"),
        (("--set", "team.init.spacng_m=3"), "(did you mean 'spacing_m'?)"),
        (("--set", "strategy.name=silnt"), "(did you mean 'silent'?)"),
        (("--set", "world.scene=fre"), "(did you mean 'free'?)"),
        (("--set", "team.init.kind=grd"), "(did you mean 'grid'?)"),
    ],
)
def test_a_misspelt_key_or_name_suggests_the_close_one(capsys, args, hint) -> None:
    code, out, err = tether(capsys, "validate", "silent_demo", *args)
    assert code == 2 and hint in err and len(err.splitlines()) == 1


def test_a_misspelt_scenario_name_suggests_the_built_in(capsys) -> None:
    code, _, err = tether(capsys, "run", "silnt_demo")
    assert code == 2 and "(did you mean 'silent_demo'?)" in err


def test_list_describes_every_name(capsys) -> None:
    code, out, _ = tether(capsys, "list")
    assert code == 0
    entries = [s for s in out.splitlines() if s.startswith("  ")]
    assert len(entries) >= 25
    for line in entries:
        name, _, description = line.strip().partition(" ")
        assert len(description.strip()) > 10, f"{name} has no description"
