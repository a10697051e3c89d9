"""A sweep's processes and folder after kills and collisions.

* ``kill -9`` of the parent of a 2-worker ``--executor processes`` sweep: no process of it
  is left after 10 s; the resume loses and repeats no trial and removes the staging
  folders the killed trials left.
* Two sweeps on one folder: one lock per folder; the second is refused in one line, at
  once, and every trial is computed once.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pyarrow.parquet as pq
import yaml

from tether.config import load_scenario

CMD = [sys.executable, "-m", "tether.cli", "sweep", "s.yaml", "--out", "out", "--seeds", "5",
       "--executor", "processes", "--workers", "2"]  # fmt: skip
ENV = {**os.environ, "MPLBACKEND": "Agg", "TETHER_JIT": "0"}


def write_sweep(tmp_path: Path, steps: int = 120) -> None:
    data = load_scenario("silent_demo").model_dump(mode="json")
    data["sim"]["max_steps"] = steps
    data["output"]["figures"] = False
    data["sweep"] = {"strategy.params.d0_m": [6.0, 9.0]}
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(data))


def children_of(pid: int) -> list[int]:
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                stat = (entry / "stat").read_text()
            except OSError:
                continue
            fields = stat.rsplit(") ", 1)[1].split()
            if int(fields[1]) == pid and fields[0] != "Z":
                found.append(int(entry.name))
    return found


def running(pid: int) -> bool:
    try:
        stat = Path(f"/proc/{pid}/stat").read_text()
    except OSError:
        return False
    return stat.rsplit(") ", 1)[1][0] != "Z"


def finished(out: Path) -> dict[str, int]:
    return {p.parent.relative_to(out).as_posix(): p.stat().st_mtime_ns
            for p in out.glob("*/seed-*/summary.json")}  # fmt: skip


def wait_until(condition, timeout_s: float, what: str) -> None:  # noqa: ANN001
    end = time.monotonic() + timeout_s
    while not condition():
        assert time.monotonic() < end, what
        time.sleep(0.05)


def test_kill_9_of_the_parent_leaves_no_process_and_resume_loses_and_repeats_nothing(tmp_path):
    write_sweep(tmp_path)
    out = tmp_path / "out"
    parent = subprocess.Popen(CMD, cwd=tmp_path, env=ENV, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL)  # fmt: skip
    try:
        wait_until(lambda: len(children_of(parent.pid)) >= 2, 120, "no 2 workers started")
        wait_until(lambda: len(finished(out)) >= 2, 240, "no trial finished in time")
        workers = children_of(parent.pid)
    finally:
        parent.send_signal(signal.SIGKILL)  # the parent only: its workers are on their own
        parent.wait(timeout=30)
    assert len(workers) >= 2
    wait_until(lambda: not any(running(w) for w in workers), 10,
               "a worker of the killed sweep was still running after 10 s")  # fmt: skip
    before = finished(out)
    assert 2 <= len(before) < 10, "killed while trials remain"

    done = subprocess.run(CMD, cwd=tmp_path, env=ENV, capture_output=True, text=True,
                          timeout=600)  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert f"10 runs ({len(before)} already done)" in done.stdout  # nothing repeated
    rows = pq.read_table(out / "sweep.parquet").to_pylist()
    assert len(rows) == 10 and all(r["status"] == "done" for r in rows)  # nothing lost
    after = finished(out)
    assert all(after[t] == m for t, m in before.items())  # finished trials untouched
    tethers = (".tether-sweep.lock", ".tether-run.json")
    hidden = [p.name for p in out.rglob(".*") if p.name not in tethers]
    assert hidden == []  # no staging folder or temporary file of the killed trials is left


def test_a_second_sweep_on_the_folder_is_refused_and_each_trial_runs_once(tmp_path):
    write_sweep(tmp_path, steps=60)
    out = tmp_path / "out"
    first = subprocess.Popen(CMD, cwd=tmp_path, env=ENV, stdout=subprocess.PIPE,
                             stderr=subprocess.PIPE, text=True)  # fmt: skip
    try:
        wait_until(lambda: (out / "store.json").exists(), 120, "the first sweep never started")
        second = subprocess.run(CMD, cwd=tmp_path, env=ENV, capture_output=True, text=True,
                                timeout=120)  # fmt: skip
        first_out, first_err = first.communicate(timeout=600)
    finally:
        if first.poll() is None:
            first.kill()
    assert second.returncode == 2, second.stderr
    lines = second.stderr.strip().splitlines()
    assert len(lines) == 1 and "another tether sweep" in lines[0], second.stderr
    assert f"process {first.pid}" in lines[0]
    assert first.returncode == 0, first_err
    assert "10 runs (0 already done)" in first_out  # every trial computed by the first, once
    third = subprocess.run(CMD, cwd=tmp_path, env=ENV, capture_output=True, text=True,
                           timeout=600)  # fmt: skip
    assert third.returncode == 0 and "10 runs (10 already done)" in third.stdout


def test_leftovers_of_killed_trials_are_removed_and_nothing_else(tmp_path, capsys, monkeypatch):
    from _cli import tether

    write_sweep(tmp_path, steps=3)
    monkeypatch.chdir(tmp_path)
    args = ("sweep", "s.yaml", "--out", "out", "--executor", "serial")
    assert tether(capsys, *args)[0] == 0
    out = tmp_path / "out"
    combo = next(p for p in out.iterdir() if p.is_dir() and p.name != "figures")
    (combo / ".seed-1.staging-abc123").mkdir()
    (combo / ".seed-1.staging-abc123" / "steps.parquet").write_bytes(b"half")
    (combo / ".seed-0.old-xyz").mkdir()
    (out / ".sweep.parquet.k2j3.tmp").write_bytes(b"half")
    (out / "notes.md").write_text("mine")  # the user's: stays
    (out / ".ipynb_checkpoints").mkdir()  # the user's hidden folders: stay
    (combo / ".notes").mkdir()
    (combo / ".notes" / "todo.txt").write_text("mine")
    code, stdout, err = tether(capsys, *args)
    assert code == 0, err
    assert "(2 already done)" in stdout
    hidden = {p.name for p in out.rglob(".*")}
    assert hidden == {".tether-sweep.lock", ".tether-run.json", ".ipynb_checkpoints", ".notes"}
    assert (out / "notes.md").read_text() == "mine"
    assert (combo / ".notes" / "todo.txt").read_text() == "mine"
