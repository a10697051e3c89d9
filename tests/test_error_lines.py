"""Inputs that broke the one-line, exit-2 promise: each is now one short line, exit code 2,
the same from ``validate`` and ``run``, with nothing printed before it."""

from __future__ import annotations

import json
import socket
from pathlib import Path

import numpy as np
import pytest
import yaml
from PIL import Image

from _cli import one_error_line, tether
from tether import runner
from tether.config import load_scenario

#: an error line stays readable: a long value is shortened, never echoed whole
MAX_LINE = 400


def one_line(code: int, err: str, *needles: str) -> str:
    return one_error_line(code, err, *needles, max_length=MAX_LINE)


def base(steps: int = 3) -> dict:
    data = load_scenario("silent_demo").model_dump(mode="json")
    data["sim"]["max_steps"] = steps
    data["output"]["figures"] = False
    return data


def on_map(tmp_path: Path, **params) -> dict:  # noqa: ANN003
    Image.fromarray(np.full((40, 60), 255, np.uint8)).save(tmp_path / "wall.png")
    data = base()
    data["world"] = {"scene": "map", "dim": 2, "params": {"path": "wall.png", **params}}
    return data


def validate_and_run(tmp_path: Path, capsys, data: dict, *needles: str, args=()) -> str:  # noqa: ANN001
    path = tmp_path / "bad.yaml"
    path.write_text(yaml.safe_dump(data, allow_unicode=True))
    code, out, err = tether(capsys, "validate", str(path), *args)
    line = one_line(code, err, *needles)
    code, _, err_run = tether(capsys, "run", str(path), "--out", str(tmp_path / "o"), *args)
    assert one_line(code, err_run) == line  # validate and run agree
    assert not (tmp_path / "o").exists()
    return line


def test_ragged_waypoints(tmp_path, capsys):
    data = base()
    data["strategy"]["params"]["trajectory"]["waypoints"] = [[0, 0], [40]]
    validate_and_run(tmp_path, capsys, data, "strategy.params.trajectory.waypoints",
                     "waypoint 1 has 1 coordinates")  # fmt: skip


def test_a_map_resolution_of_1e308(tmp_path, capsys):
    data = on_map(tmp_path, resolution_m=1e308)
    validate_and_run(tmp_path, capsys, data, "bad.yaml: world.params.resolution_m: 1e+308 m",
                     "wide")  # fmt: skip


@pytest.mark.parametrize("on_a_map", [True, False])
def test_an_unknown_scene_parameter_is_its_own_field(tmp_path, capsys, on_a_map):
    """Not the map's ``world.params.path``: the misspelt key, with the close one."""
    data = on_map(tmp_path) if on_a_map else base()
    data["world"]["params"]["resolution"] = 0.1
    validate_and_run(tmp_path, capsys, data, "bad.yaml: world.params.resolution: unknown",
                     "did you mean 'resolution_m'?" if on_a_map else "(accepted: dim,")  # fmt: skip


def test_a_map_path_longer_than_a_file_name_may_be(tmp_path, capsys):
    data = on_map(tmp_path)
    data["world"]["params"]["path"] = "m" * 8000 + ".png"
    validate_and_run(tmp_path, capsys, data, "world.params.path", "File name too long")


NOISY = """
import warnings
import numpy as np
from tether import cli, runner
from tether.errors import ScenarioError

def noisy(*args, **kwargs):
    np.seterr(over="warn")
    np.float64(1e308) * np.float64(10)  # numpy prints a RuntimeWarning
    warnings.warn("overflow encountered in multiply", RuntimeWarning, stacklevel=1)
    raise ScenarioError("silent_demo: world.params: refused")

runner.build_world = noisy
cli.main(["validate", "silent_demo"])
"""


def test_no_numpy_warning_before_the_error_line():
    import subprocess
    import sys

    proc = subprocess.run([sys.executable, "-c", NOISY], capture_output=True, text=True,
                          timeout=120)  # fmt: skip
    one_line(proc.returncode, proc.stderr, "world.params: refused")


NAMES = [("😀" * 100, "at most 100 bytes"), ("a\nb", "printable"), ("a\tb", "printable")]


@pytest.mark.parametrize(("name", "needle"), NAMES)
def test_a_name_that_cannot_be_a_folder_is_refused(tmp_path, capsys, name, needle):
    data = base()
    data["name"] = name
    validate_and_run(tmp_path, capsys, data, "name", needle)


def test_a_name_of_100_bytes_runs(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    data = base()
    data["name"] = "😀" * 25
    path = tmp_path / "ok.yaml"
    path.write_text(yaml.safe_dump(data, allow_unicode=True))
    code, _, err = tether(capsys, "run", str(path), "--no-figures")
    assert code == 0, err


def test_a_negative_collision_distance(tmp_path, capsys):
    data = base()
    data["sim"]["collision_distance_m"] = -2
    validate_and_run(tmp_path, capsys, data, "sim.collision_distance_m")


def test_run_refuses_a_sweep_combination_validate_refuses(tmp_path, capsys):
    data = base()
    data["sweep"] = {"team.init.spacing_m": [8.0, 100.0]}  # 100 m apart: not connected at 15 m
    validate_and_run(tmp_path, capsys, data, "sweep: combination", "spacing_m=100.0")


def test_run_refuses_a_quick_entry_validate_refuses(tmp_path, capsys):
    data = base()
    data["sweep"] = {"strategy.params.d0_m": [6.0, 9.0],
                     "quick": {"axes": {"strategy.params.d0_m": [-1.0]}}}  # fmt: skip
    validate_and_run(tmp_path, capsys, data, "quick size", "strategy.params.d0_m")


def test_a_port_in_use_for_view_serve(tmp_path, capsys):
    run_dir = runner.run(base(), out_dir=tmp_path / "run").path
    with socket.socket() as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        code, out, err = tether(capsys, "view", str(run_dir), "--serve", "--port", str(port))
    one_line(code, err, f"--port {port}", "in use")
    assert not (run_dir / "replay.html").exists()  # refused before any work


@pytest.mark.parametrize("content", ['{"scenario": ', "[1, 2]", '"text"', "\xff\xfe",
                                     '{"base_m": "q"}'])  # fmt: skip
@pytest.mark.parametrize("command", ["view", "animate", "export"])
def test_a_corrupt_summary(tmp_path, capsys, content, command):
    run_dir = runner.run(base(), out_dir=tmp_path / "run").path
    (run_dir / "summary.json").write_bytes(content.encode("latin-1"))
    code, _, err = tether(capsys, command, str(run_dir), "--out", str(tmp_path / "x"))
    one_line(code, err, "summary.json")
    json.dumps(err)  # printable
