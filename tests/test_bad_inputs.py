"""A corpus of bad inputs: every one ends in exit code 2 and one line naming file and field.

Each scenario-file case is run through ``tether validate`` and ``tether run``
(in-process, through :func:`tether.cli.main`): both must exit with code 2,
print exactly one ``error:`` line on stderr naming the file and the field, print
the *same* line (validate and run agree), print no traceback, and leave no run
folder behind. Command-line cases (usage errors, bad options, bad ``--out``)
check the same one-line contract (the corpus itself: ``tests/_bad_input_cases.py``). A
few cases run as real subprocesses at the end, to show the installed entry point behaves
as the in-process one.
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest
import yaml

from _bad_input_cases import CASES, connectivity, recurrent, silent, utility, write_case
from _cli import tether
from tether import cli

# --------------------------------------------------------------------------- harness


def assert_one_line(code: int, err: str, *needles: str) -> str:
    assert code == 2, err
    assert "Traceback" not in err, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    line = lines[0]
    assert line.startswith("error: "), line
    assert "internal error" not in line, line
    for needle in needles:
        assert needle in line, f"{needle!r} not in {line!r}"
    return line


def test_the_corpus_is_large_enough():
    assert len(CASES) + len(COMMAND_LINES) + len(OUT_CASES) >= 60


@pytest.mark.parametrize("name", list(CASES))
def test_validate_and_run_refuse_with_the_same_line(name, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    case = CASES[name]
    path = write_case(case, tmp_path)
    code, _, err = tether(capsys, "validate", str(path), *case.args)
    line = assert_one_line(code, err, case.field)
    if not case.field.startswith("--set"):
        assert "bad.yaml" in line
    code, _, err_run = tether(capsys, "run", str(path), "--out", "out", "--no-figures", *case.args)
    assert assert_one_line(code, err_run, case.field) == line  # validate and run agree
    assert not (tmp_path / "out").exists()
    if name.startswith("sweep:"):  # `tether sweep` refuses the same, before any trial
        code, _, err_sweep = tether(capsys, "sweep", str(path), "--out", "sw", *case.args)
        assert assert_one_line(code, err_sweep, case.field) == line
        assert not (tmp_path / "sw").exists()
    assert not [p for p in tmp_path.iterdir() if ".staging" in p.name]


def test_good_versions_of_the_bases_validate(tmp_path, capsys, monkeypatch):
    """The corpus's bases are valid: each bad case is bad because of its one change."""
    monkeypatch.chdir(tmp_path)
    for base in (silent, connectivity, recurrent, utility):
        path = tmp_path / "good.yaml"
        path.write_text(yaml.safe_dump(base(tmp_path)))
        code, out, err = tether(capsys, "validate", str(path))
        assert code == 0, err
        assert "ok" in out


# --------------------------------------------------------------------------- command lines

COMMAND_LINES: dict[str, tuple[tuple[str, ...], str]] = {
    "unknown command": (("fly",), "No such command 'fly'"),
    "run --seed abc": (("run", "--seed", "abc"), "--seed"),
    "run --seed -1": (("run", "--seed", "-1"), "--seed"),
    "run --seed 2**64": (("run", "--seed", str(2**64)), "--seed"),
    "run unknown option": (("run", "--bogus"), "--bogus"),
    "run --no-figures true": (("run", "--no-figures", "true"), "--no-figures"),
    "run --out without value": (("run", "--out"), "--out"),
    "validate without scenario": (("validate",), "scenario"),
    "validate missing file": (("validate", "nowhere.yaml"), "nowhere.yaml: file not found"),
    "run a folder": (("run", "."), "is a folder"),
    "run two scenarios": (("run", "silent_demo", "silent_paper"), "silent_paper"),
    "sweep --seeds 0": (("sweep", "silent_paper", "--seeds", "0"), "--seeds"),
    "sweep --seeds -3": (("sweep", "silent_paper", "--seeds", "-3"), "--seeds"),
    "sweep --workers 0": (("sweep", "silent_paper", "--workers", "0"), "--workers"),
    "sweep unknown executor": (("sweep", "silent_paper", "--executor", "spark"), "spark"),
    "sweep --address without dask": (
        ("sweep", "silent_paper", "--address", "tcp://127.0.0.1:9"),
        "--address",
    ),
    "sweep too many trials": (("sweep", "silent_paper", "--seeds", "10000000"), "sweep"),
    "animate a missing run folder": (("animate", "nowhere"), "nowhere: not a run folder"),
    "animate --stride 0": (("animate", "nowhere", "--stride", "0"), "--stride"),
    "animate --width 0": (("animate", "nowhere", "--width", "0"), "--width"),
    "view --port -5": (("view", "nowhere", "--serve", "--port", "-5"), "--port"),
    "export a missing run folder": (("export", "nowhere"), "nowhere"),
}


@pytest.mark.parametrize("name", list(COMMAND_LINES))
def test_command_line_errors_are_one_line(name, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    args, needle = COMMAND_LINES[name]
    code, _, err = tether(capsys, *args)
    assert_one_line(code, err, needle)
    assert not (tmp_path / "runs").exists()


def test_a_dead_dask_address_fails_fast_in_one_line(tmp_path, capsys, monkeypatch):
    pytest.importorskip("distributed")
    monkeypatch.chdir(tmp_path)
    import socket
    import time

    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    start = time.perf_counter()
    code, _, err = tether(
        capsys,
        "sweep",
        "silent_paper",
        "--out",
        "sw",
        "--executor",
        "dask",
        "--address",
        f"tcp://127.0.0.1:{port}",
    )
    assert time.perf_counter() - start < 20
    assert_one_line(code, err, f"--address tcp://127.0.0.1:{port}", "dask scheduler")


# --------------------------------------------------------------------------- --out


def _ro_dir(tmp: Path) -> str:
    return "/proc/tether-cannot-write/run"


OUT_CASES: dict[str, Callable[[Path], str]] = {
    "a file": lambda t: (t / "f.txt").write_text("x") and "f.txt",
    "under a file": lambda t: (t / "f.txt").write_text("x") and "f.txt/run",
    "read-only place": _ro_dir,
    "non-empty folder of other files": lambda t: (
        (
            (t / "mine").mkdir(),
            (t / "mine" / "notes.txt").write_text("keep me"),
        )
        and "mine"
    ),
    "name too long": lambda t: "x" * 300,
}


@pytest.mark.parametrize("name", list(OUT_CASES))
@pytest.mark.parametrize("command", ["run", "sweep"])
def test_bad_out_is_one_line_and_leaves_nothing(name, command, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    scenario = tmp_path / "s.yaml"
    data = silent(tmp_path)
    data["sim"]["max_steps"] = 3
    scenario.write_text(yaml.safe_dump(data))
    out = OUT_CASES[name](tmp_path)
    before = sorted(p.name for p in tmp_path.rglob("*"))
    args = ["--no-figures"] if command == "run" else []
    code, _, err = tether(capsys, command, str(scenario), "--out", out, *args)
    assert_one_line(code, err, "--out")
    after = sorted(p.name for p in tmp_path.rglob("*"))
    assert after == before  # no run folder, no staging folder, no parent folder left


def test_an_unwritable_output_dir_is_refused_by_validate_and_run(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "f.txt").write_text("x")
    data = silent(tmp_path)
    data["output"] = {"dir": "f.txt/runs"}
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump(data))
    for command in ("validate", "run"):
        code, _, err = tether(capsys, command, "bad.yaml")
        assert_one_line(code, err, "f.txt/runs", "cannot create")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.yaml", "f.txt"]
    code, out, err = tether(capsys, "validate", "silent_demo")  # a valid one leaves nothing
    assert code == 0 and "ok" in out, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.yaml", "f.txt"]


def test_rerun_into_the_same_out_replaces_the_folder(tmp_path, capsys, monkeypatch):
    """Reusing --out never mixes two runs' files: the second run replaces the first whole."""
    monkeypatch.chdir(tmp_path)
    short = silent(tmp_path)
    short["sim"]["max_steps"] = 3
    (tmp_path / "a.yaml").write_text(yaml.safe_dump(short))
    code, _, err = tether(capsys, "run", "a.yaml", "--out", "out")
    assert code == 0, err
    assert (tmp_path / "out" / "figures" / "links.png").exists()
    code, _, err = tether(capsys, "run", "a.yaml", "--out", "out", "--no-figures")
    assert code == 0, err
    names = {p.name for p in (tmp_path / "out").iterdir()}
    assert "figures" not in names
    assert "summary.json" in names
    (tmp_path / "out" / "stray.txt").write_text("left by hand")  # the user's: never deleted
    code, _, err = tether(capsys, "run", "a.yaml", "--out", "out")
    assert_one_line(code, err, "stray.txt", "did not write")
    assert (tmp_path / "out" / "stray.txt").read_text() == "left by hand"


def test_a_failed_run_leaves_no_folder(tmp_path, capsys, monkeypatch):
    """A run that fails while simulating (an internal error) removes everything it staged."""
    monkeypatch.chdir(tmp_path)
    from tether.silent.strategy import SilentStrategy

    def boom(self, ctx):
        raise RuntimeError("strategy exploded")

    monkeypatch.setattr(SilentStrategy, "step", boom)
    code, _, err = tether(capsys, "run", "silent_demo", "--out", "deep/inside/out")
    assert code == 1
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "internal error RuntimeError: strategy exploded" in lines[0]
    assert "TETHER_DEBUG=1" in lines[0]
    assert list(tmp_path.iterdir()) == []


def test_a_full_disk_is_one_line_and_leaves_nothing(tmp_path, capsys, monkeypatch):
    import errno

    from tether import runfolder

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(runfolder, "write_table", full)
    data = silent(tmp_path)
    data["sim"]["max_steps"] = 3
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(data))
    code, _, err = tether(capsys, "run", "s.yaml", "--out", "out/run", "--no-figures")
    assert_one_line(code, err, "out/run: cannot write the run folder (No space left on device)")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.yaml"]


def test_internal_error_keeps_exit_1_and_traceback_on_request(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    from tether.silent.strategy import SilentStrategy

    def boom(self, ctx):
        raise RuntimeError("strategy exploded")

    monkeypatch.setattr(SilentStrategy, "step", boom)
    monkeypatch.setenv("TETHER_DEBUG", "1")
    with pytest.raises(RuntimeError, match="strategy exploded"):
        cli.main(["run", "silent_demo", "--out", "out"])


# --------------------------------------------------------------------------- subprocesses


def _proc(*args: str, cwd: Path, env: dict[str, str] | None = None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "tether.cli", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, **(env or {})},
    )


@pytest.mark.parametrize(
    "args",
    [("fly",), ("run", "--seed", "abc"), ("validate", "bad.yaml")],
    ids=["unknown-command", "seed-abc", "bad-file"],
)
def test_real_processes_print_one_line(tmp_path, args):
    (tmp_path / "bad.yaml").write_bytes(b"name: caf\xe9\n")
    proc = _proc(*args, cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert proc.stderr.startswith("error: ")


def test_real_process_without_click_importable(tmp_path):
    """typer bundles click; tether must not need the `click` package (the README install)."""
    blocker = tmp_path / "block"
    blocker.mkdir()
    (blocker / "click.py").write_text("raise ImportError('click is not installed here')\n")
    env = {"PYTHONPATH": os.pathsep.join([str(blocker), os.environ.get("PYTHONPATH", "")])}
    typer_alone = subprocess.run(
        [sys.executable, "-c", "import typer"], capture_output=True, env={**os.environ, **env}
    )
    if typer_alone.returncode != 0:
        pytest.skip("this typer imports click itself (typer < 0.22 did)")
    for args in [("fly",), ("run", "--bogus"), ("run", "--seed", "abc")]:
        proc = _proc(*args, cwd=tmp_path, env=env)
        assert proc.returncode == 2, proc.stderr
        assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
