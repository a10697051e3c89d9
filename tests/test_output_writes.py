"""``tether view``, ``animate`` and ``export`` write whole files, never through a link,
under names safe from data, and a disk that cannot take them is one line (exit 2)."""

from __future__ import annotations

import json
import os
import resource
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from _cli import one_error_line, tether
from tether.config import load_scenario
from tether.runfolder import read_marker
from tether.runner import run

OUTPUTS = {  # command -> (extra args, the default output file in the run folder)
    "view": ((), "replay.html"),
    "animate": (("--duration", "0.5", "--fps", "4"), "animation.gif"),
    "export": (("--format", "mcap"), "silent_demo.mcap"),
}


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory) -> Path:
    sc = load_scenario("silent_demo")
    sc.sim.max_steps = 6
    sc.output.figures = False
    return run(sc, out_dir=tmp_path_factory.mktemp("runs") / "run").path


def leftovers(folder: Path) -> list[str]:
    return [p.name for p in folder.iterdir() if p.name.endswith(".tmp") or "staging" in p.name]


@pytest.mark.parametrize("command", list(OUTPUTS))
def test_a_link_at_the_output_is_refused_and_its_target_untouched(
    command, run_dir, tmp_path, capsys
):
    args, name = OUTPUTS[command]
    precious = tmp_path / "thesis.tex"
    precious.write_text("my thesis")
    link = run_dir / name
    link.symlink_to(precious)
    try:
        code, _, err = tether(capsys, command, str(run_dir), *args)
        one_error_line(code, err, name, "symbolic link")
        assert precious.read_text() == "my thesis" and link.is_symlink()
        code, _, err = tether(capsys, command, str(run_dir), *args, "--out", str(link))
        one_error_line(code, err, "symbolic link")
        assert precious.read_text() == "my thesis"
    finally:
        link.unlink()
    assert leftovers(run_dir) == []


@pytest.mark.parametrize("command", list(OUTPUTS))
def test_outputs_in_the_run_folder_are_whole_and_recorded_as_tethers(command, run_dir, capsys):
    args, name = OUTPUTS[command]
    code, _, err = tether(capsys, command, str(run_dir), *args)
    assert code == 0, err
    assert (run_dir / name).stat().st_size > 0
    assert name in read_marker(run_dir)["files"]  # a later --out may replace it
    assert leftovers(run_dir) == []


def test_export_names_its_file_safely_from_summary_data(run_dir, tmp_path, capsys):
    """summary.json's ``scenario`` is data: ``../../x`` must not escape the run folder."""
    copy = tmp_path / "copy"
    copy.mkdir()
    for path in run_dir.iterdir():
        if path.suffix in (".parquet", ".json", ".yaml"):
            (copy / path.name).write_bytes(path.read_bytes())
    summary = json.loads((copy / "summary.json").read_text())
    summary["scenario"] = "../../escaped"
    (copy / "summary.json").write_text(json.dumps(summary))
    before = set(tmp_path.parent.rglob("*escaped*"))
    code, out, err = tether(capsys, "export", str(copy))
    assert code == 0, err
    made = [p for p in copy.iterdir() if p.suffix == ".mcap"]
    assert len(made) == 1 and "escaped" in made[0].name and "/" not in made[0].name
    assert set(tmp_path.parent.rglob("*escaped*")) - before == {made[0]}


def _limited(limit_bytes: int):  # noqa: ANN202
    def preexec() -> None:
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # writes beyond the limit fail (EFBIG)
        resource.setrlimit(resource.RLIMIT_FSIZE, (limit_bytes, limit_bytes))

    return preexec


@pytest.mark.parametrize("command", list(OUTPUTS))
def test_a_disk_that_fills_up_leaves_the_previous_file_and_one_line(command, run_dir, tmp_path):
    args, name = OUTPUTS[command]
    target = tmp_path / name
    target.write_bytes(b"previous complete file")
    proc = subprocess.run(
        [sys.executable, "-m", "tether.cli", command, str(run_dir), *args, "--out", str(target)],
        capture_output=True, text=True, timeout=300, preexec_fn=_limited(2000),
        env=dict(os.environ, TETHER_JIT="0"),
    )  # fmt: skip
    one_error_line(proc.returncode, proc.stderr, str(target), "cannot write")
    assert target.read_bytes() == b"previous complete file"  # never a truncated file
    assert leftovers(tmp_path) == []


@pytest.mark.parametrize("command", list(OUTPUTS))
def test_a_folder_that_cannot_be_written_is_one_line(command, run_dir, tmp_path, capsys,
                                                     monkeypatch):  # fmt: skip
    import tempfile

    def read_only(*a, **k):  # noqa: ANN002, ANN003, ANN202 - as a read-only folder answers
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(tempfile, "mkstemp", read_only)
    monkeypatch.setattr(tempfile, "mkdtemp", read_only)
    args, name = OUTPUTS[command]
    code, _, err = tether(capsys, command, str(run_dir), *args, "--out", str(tmp_path / name))
    one_error_line(code, err, "Permission denied")
    assert not (tmp_path / name).exists()
