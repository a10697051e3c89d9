"""One bounded YAML reader for every YAML file tether reads.

Scenarios, campaigns, ROS map YAML, a sweep folder's ``sweep.yaml`` and ``--set`` values:
aliases that expand beyond the bound, nesting too deep, duplicate keys, oversized files
and Python tags are refused in one line (exit 2), quickly.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from PIL import Image

from _cli import one_error_line, tether
from tether.config import load_scenario
from tether.errors import MapError, ScenarioError
from tether.yamlfile import MAX_YAML_BYTES, MAX_YAML_DEPTH, MAX_YAML_VALUES, parse_yaml, read_yaml

BOMB = "\n".join(
    ["a0: &a0 [x, x, x, x, x, x, x, x, x, x]"]
    + [f"a{k}: &a{k} [{', '.join([f'*a{k - 1}'] * 10)}]" for k in range(1, 9)]
)  # 10**9 values once expanded, a few hundred bytes of text


def map_scenario(tmp_path: Path, map_yaml_text: str) -> Path:
    Image.fromarray(np.full((20, 20), 255, np.uint8)).save(tmp_path / "room.png")
    (tmp_path / "room.yaml").write_text(map_yaml_text)
    data = load_scenario("silent_demo").model_dump(mode="json")
    data["world"] = {"scene": "map", "dim": 2, "params": {"path": "room.yaml"}}
    data["team"]["n_robots"] = 2
    data["team"]["init"] = {"kind": "positions", "positions": [[5, 5], [6, 5]]}
    data["strategy"]["params"]["trajectory"]["waypoints"] = [[5, 5], [8, 5]]
    path = tmp_path / "scenario.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


GOOD_MAP = "image: room.png\nresolution: 0.5\norigin: [0.0, 0.0, 0.0]\nnegate: 0\n"
GOOD_MAP += "occupied_thresh: 0.65\nfree_thresh: 0.196\n"


def test_an_alias_bomb_in_a_map_yaml_is_refused_quickly(tmp_path):
    """It hung (370 MB and growing after 40 s); a subprocess bounds the test in time."""
    path = map_scenario(tmp_path, GOOD_MAP + BOMB + "\nextra: *a8\n")
    proc = subprocess.run(
        [sys.executable, "-m", "tether.cli", "validate", str(path)],
        capture_output=True, text=True, timeout=120, cwd=tmp_path,
    )  # fmt: skip
    one_error_line(proc.returncode, proc.stderr, "room.yaml", "alias")


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        (GOOD_MAP + "resolution: 0.25\n", "given twice"),
        (GOOD_MAP + "deep: " + "[" * (MAX_YAML_DEPTH + 5) + "]" * (MAX_YAML_DEPTH + 5), "nested"),
        (GOOD_MAP + "x: !!python/object/apply:os.system [echo hi]\n", "remove the tag"),
    ],
)
def test_a_bad_map_yaml_is_one_line(tmp_path, capsys, text, needle):
    path = map_scenario(tmp_path, text)
    code, _, err = tether(capsys, "validate", str(path))
    one_error_line(code, err, "room.yaml", needle)
    code, _, err_run = tether(capsys, "run", str(path), "--out", str(tmp_path / "o"))
    assert one_error_line(code, err_run) == err.strip()


def test_the_good_map_yaml_validates(tmp_path, capsys):
    code, _, err = tether(capsys, "validate", str(map_scenario(tmp_path, GOOD_MAP)))
    assert code == 0, err


def test_an_oversized_map_yaml_is_refused_before_it_is_read(tmp_path, monkeypatch):
    path = tmp_path / "big.yaml"
    with open(path, "wb") as fh:
        fh.truncate(MAX_YAML_BYTES + 1)  # sparse: no real disk use

    def no_parse(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        raise AssertionError("parsed")

    monkeypatch.setattr(yaml, "load", no_parse)
    with pytest.raises(MapError, match="at most 16 MiB"):
        read_yaml(path, str(path), MapError, what="a map YAML file")


@pytest.mark.parametrize(
    ("text", "needle"),
    [
        ("sensing:\n  range_m: 5\n  range_m: 6\n", "'range_m' is given twice"),
        ("name: a\nname: b\n", "'name' is given twice"),
        ("a: " + "{b: " * 100 + "1" + "}" * 100, "nested"),
        (BOMB, "alias"),
        (
            "a: &x [1]\nb: &y [*x]\n"
            + "".join(f"c{k}: &z{k} [*{'y' if k == 0 else f'z{k - 1}'}]\n" for k in range(80)),
            "nested",
        ),  # fmt: skip
        ("a: !!python/name:os.system\n", "remove the tag"),
        ("sweep: {zip: [[a, !!set {x: null}]]}\n", "tag !!set is not plain data"),
        ("a: !!binary aGk=\n", "tag !!binary"),
        ("a: !!timestamp 2001-12-14\n", "tag !!timestamp"),
        ("a: !mine x\n", "tag !mine"),
    ],
)
def test_scenario_yaml_is_bounded_and_strict(text, needle):
    with pytest.raises(ScenarioError, match=needle):
        parse_yaml(text, "s.yaml")


def wide_aliases(references: int) -> str:
    """A list of 1,000 values, and a list of ``references`` aliases to it: each alias is
    1,001 values once expanded (the list and its items), no one of them near the bound."""
    return "a: &a [" + ", ".join(["x"] * 1000) + "]\nb: [" + ", ".join(["*a"] * references) + "]\n"


def test_the_alias_bound_counts_every_value_of_the_expanded_document():
    assert MAX_YAML_VALUES == 1 + 999 * 1001  # 999 aliases fit exactly, 1,000 do not
    assert len(parse_yaml(wide_aliases(999), "s.yaml")["b"]) == 999
    with pytest.raises(ScenarioError, match="s.yaml: b: YAML aliases expand to more than"):
        parse_yaml(wide_aliases(1000), "s.yaml")


def test_plain_tags_are_read_and_dates_stay_text():
    text = "a: !!str 5\nb: !!float 1\nc: 2001-12-14\nd: !!int '7'\n"
    assert parse_yaml(text, "s.yaml") == {"a": "5", "b": 1.0, "c": "2001-12-14", "d": 7}


def test_merge_keys_may_be_overridden_without_being_duplicates():
    text = "base: &b {x: 1, y: 2}\nuse:\n  <<: *b\n  x: 3\n"
    assert parse_yaml(text, "s.yaml")["use"] == {"x": 3, "y": 2}


def test_duplicate_keys_in_a_scenario_file_and_in_set_are_one_line(tmp_path, capsys):
    path = tmp_path / "dup.yaml"
    data = load_scenario("silent_demo").model_dump(mode="json")
    text = yaml.safe_dump(data) + "seed: 3\n"  # seed given twice
    path.write_text(text)
    code, _, err = tether(capsys, "validate", str(path))
    line = one_error_line(code, err, "dup.yaml", "'seed' is given twice")
    code, _, err = tether(capsys, "run", str(path), "--out", str(tmp_path / "o"))
    assert one_error_line(code, err) == line and not (tmp_path / "o").exists()
    code, _, err = tether(capsys, "validate", "silent_demo", "--set", "sim={dt_s: 1, dt_s: 2}")
    one_error_line(code, err, "--set sim", "given twice")


def test_a_sweep_folder_with_a_bomb_in_sweep_yaml_does_not_hang(tmp_path):
    """``sweep.yaml`` of a sweep folder is read with the same bounds (resume, report)."""
    from tether.experiments.store import open_store

    scenario = load_scenario("silent_demo")
    out = tmp_path / "sweep"
    open_store(scenario, out)
    (out / "sweep.yaml").write_text(BOMB)
    assert open_store(scenario, out) == out  # the recorded hash decides; the bomb is ignored


def test_a_pipe_is_not_read(tmp_path):
    import os

    fifo = tmp_path / "pipe.yaml"
    os.mkfifo(fifo)
    with pytest.raises(ScenarioError, match="not a regular file"):
        load_scenario(fifo)
