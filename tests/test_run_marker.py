"""A run folder is recognised by tether's own marker, never by common file names.

``--out`` onto anything that is not an empty folder or a tether run folder holding only
what tether wrote is refused in one line, and nothing there is touched.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import pytest

from _cli import tether
from tether.config import load_scenario, scenario_from_dict
from tether.errors import OutputError
from tether.runfolder import MARKER, is_run_folder, read_marker, record_output
from tether.runner import run


def tiny(max_steps: int = 3):
    data = load_scenario("silent_demo").model_dump(mode="json")
    data["sim"]["max_steps"] = max_steps
    data["output"]["figures"] = False
    return scenario_from_dict(data, "tiny.yaml")


def snapshot(path: Path) -> dict[str, bytes | None]:
    """Every entry under ``path`` with its bytes (None for folders)."""
    return {
        str(p.relative_to(path)): (p.read_bytes() if p.is_file() else None)
        for p in sorted(path.rglob("*"))
    }


def test_a_folder_with_scenario_and_summary_names_is_not_a_run_folder(tmp_path, capsys):
    """The reported loss: scenario.yaml, summary.json, thesis.tex and notes/ all gone."""
    mine = tmp_path / "thesis"
    (mine / "notes").mkdir(parents=True)
    (mine / "scenario.yaml").write_text("my scenario draft\n")
    (mine / "summary.json").write_text('{"mine": true}\n')
    (mine / "thesis.tex").write_text("\\documentclass{article}\n")
    (mine / "notes" / "a.txt").write_text("notes\n")
    before = snapshot(mine)
    code, _, err = tether(capsys, "run", "silent_demo", "--out", str(mine), "--no-figures",
                          "--set", "sim.max_steps=3")  # fmt: skip
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: ") and str(mine) in lines[0]
    assert MARKER in lines[0]
    assert snapshot(mine) == before  # nothing touched
    assert sorted(p.name for p in tmp_path.iterdir()) == ["thesis"]  # nothing beside it


def test_a_run_folder_carries_a_marker_with_the_version_and_its_files(tmp_path):
    out = tmp_path / "run"
    run(tiny(), out_dir=out)
    marker = read_marker(out)
    assert marker is not None and marker["format"] == 1
    assert marker["tether_version"]
    assert set(marker["files"]) == {p.name for p in out.iterdir()} - {MARKER}


@pytest.mark.parametrize(
    "content",
    [
        "",
        "{}",
        '{"kind": "tether run folder", "format": 99, "tether_version": "9", "files": []}',
        '{"kind": "something else", "format": 1, "tether_version": "0.1.0", "files": []}',
        '["kind", "tether run folder"]',
        "not json",
    ],
)
def test_only_a_valid_marker_of_a_known_format_counts(tmp_path, content):
    out = tmp_path / "run"
    run(tiny(), out_dir=out)
    (out / MARKER).write_text(content)
    assert not is_run_folder(out)
    before = snapshot(out)
    with pytest.raises(OutputError, match="not a tether run folder"):
        run(tiny(), out_dir=out, seed=5)
    assert snapshot(out) == before


def test_a_marker_that_is_a_link_does_not_count(tmp_path):
    real = tmp_path / "run"
    run(tiny(), out_dir=real)
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "data.csv").write_text("1,2\n")
    (mine / MARKER).symlink_to(real / MARKER)
    assert not is_run_folder(mine)
    with pytest.raises(OutputError):
        run(tiny(), out_dir=mine)
    assert (mine / "data.csv").read_text() == "1,2\n"


def test_a_user_file_put_into_a_run_folder_stops_the_replacement(tmp_path):
    out = tmp_path / "run"
    run(tiny(), out_dir=out)
    (out / "my_notes.md").write_text("keep me")
    before = snapshot(out)
    with pytest.raises(OutputError, match="my_notes.md"):
        run(tiny(), out_dir=out, seed=2)
    assert snapshot(out) == before


def test_a_user_file_put_in_while_the_run_simulates_stops_the_commit(tmp_path, monkeypatch):
    from tether import runner

    out = tmp_path / "run"
    run(tiny(), out_dir=out)
    real = runner.simulate

    def simulate_then_user_writes(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        result = real(*args, **kwargs)
        (out / "late.txt").write_text("written during the run")
        return result

    monkeypatch.setattr(runner, "simulate", simulate_then_user_writes)
    with pytest.raises(OutputError, match="late.txt"):
        run(tiny(), out_dir=out, seed=2)
    assert (out / "late.txt").read_text() == "written during the run"
    assert json.loads((out / "summary.json").read_text())["seed"] != 2
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def test_outputs_tether_adds_later_are_its_own(tmp_path):
    out = tmp_path / "run"
    run(tiny(), out_dir=out)
    (out / "replay.html").write_text("<html></html>")
    record_output(out, "replay.html")
    run(tiny(), out_dir=out, seed=2)  # replaced: every entry was tether's
    assert not (out / "replay.html").exists()


def test_out_dot_inside_a_run_folder_leaves_nothing_behind(tmp_path, capsys, monkeypatch):
    out = tmp_path / "run"
    run(tiny(), out_dir=out)
    monkeypatch.chdir(out)
    code, _, err = tether(capsys, "run", "silent_demo", "--out", ".", "--no-figures",
                          "--set", "sim.max_steps=3", "--seed", "4")  # fmt: skip
    assert code == 0, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]  # no ..old-*, no staging
    assert json.loads((out / "summary.json").read_text())["seed"] == 4
    assert not [p.name for p in out.iterdir() if ".old-" in p.name or "staging" in p.name]


def test_a_link_at_out_is_refused_and_its_target_untouched(tmp_path):
    target = tmp_path / "target"
    run(tiny(), out_dir=target)
    before = snapshot(target)
    link = tmp_path / "link"
    os.symlink(target, link)
    with pytest.raises(OutputError, match="symbolic link"):
        run(tiny(), out_dir=link, seed=9)
    assert link.is_symlink() and snapshot(target) == before
