"""The sweep folder as a trusted store: kill -9 and resume, changed scenarios refused,
one status table readable by other tools, the same table on Dask as on local processes."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pyarrow.parquet as pq
import pytest
import yaml

from _cli import tether as _tether
from tether.config import load_scenario, scenario_from_dict
from tether.experiments.store import STORE_FILE, scenario_hash
from tether.experiments.sweep import run_sweep

#: columns that measure the machine, not the trial (may differ run to run)
TIMING = {"wall_time_s", "cpu_time_s", "planning_time_mean_s", "planning_time_max_s", "run_dir"}


def _data(steps: int = 6, sweep: dict | None = None) -> dict:
    data = load_scenario("silent_demo").model_dump(mode="json")
    data["sim"]["max_steps"] = steps
    data["output"]["figures"] = False
    data["sweep"] = sweep or {"strategy.params.d0_m": [6.0, 9.0]}
    return data


def _by_id(table: Path) -> dict[str, dict]:
    return {r["trial_id"]: r for r in pq.read_table(table).to_pylist()}


def test_resume_after_kill_9_loses_no_trial_and_redoes_none(tmp_path):
    """A real `tether sweep` process killed with SIGKILL mid-sweep, then run again."""
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(_data(steps=120)))
    cmd = [sys.executable, "-m", "tether.cli", "sweep", "s.yaml", "--out", "out", "--seeds", "5",
           "--executor", "processes", "--workers", "2"]  # fmt: skip
    env = {**os.environ, "MPLBACKEND": "Agg"}
    proc = subprocess.Popen(cmd, cwd=tmp_path, env=env, start_new_session=True,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)  # fmt: skip
    out = tmp_path / "out"
    deadline = time.monotonic() + 240
    try:
        while len(list(out.glob("*/seed-*/summary.json"))) < 2:
            assert proc.poll() is None, "the sweep ended before it could be killed"
            assert time.monotonic() < deadline, "no trial finished in time"
            time.sleep(0.05)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)  # the sweep and its worker processes, no cleanup
        proc.wait(timeout=30)
    before = {p.parent.relative_to(out).as_posix(): p.stat().st_mtime_ns
              for p in out.glob("*/seed-*/summary.json")}  # fmt: skip
    assert 2 <= len(before) < 10, "kill while trials remain"
    assert not (out / "sweep.parquet").exists()  # killed before the end

    done = subprocess.run(cmd, cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert f"10 runs ({len(before)} already done)" in done.stdout  # none redone
    rows = _by_id(out / "sweep.parquet")
    assert len(rows) == 10 and all(r["status"] == "done" for r in rows.values())  # none lost
    for trial, mtime in before.items():  # finished trials untouched
        assert (out / trial / "summary.json").stat().st_mtime_ns == mtime
        assert rows[trial]["status"] == "done"
    assert sorted(rows) == sorted(p.parent.relative_to(out).as_posix()
                                  for p in out.glob("*/seed-*/summary.json"))  # fmt: skip


def test_a_changed_scenario_is_refused_never_mixed(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    Path("s.yaml").write_text(yaml.safe_dump(_data()))
    code, _, err = _tether(capsys, "sweep", "s.yaml", "--out", "out", "--executor", "serial")
    assert code == 0, err
    table = Path("out/sweep.parquet")
    stamp, rows = table.stat().st_mtime_ns, _by_id(table)
    code, _, err = _tether(capsys, "sweep", "s.yaml", "--out", "out", "--set", "team.n_robots=5")
    assert code == 2
    [line] = err.strip().splitlines()
    assert line.startswith("error: out: holds the trials of another scenario")
    assert "team.n_robots: 12 -> 5" in line and "new --out" in line
    assert table.stat().st_mtime_ns == stamp and _by_id(table) == rows  # nothing touched
    # the same change into a new folder runs; the old folder still resumes unchanged
    code, _, err = _tether(capsys, "sweep", "s.yaml", "--out", "out5", "--set",
                           "team.n_robots=5", "--executor", "serial")  # fmt: skip
    assert code == 0, err
    code, out, err = _tether(capsys, "sweep", "s.yaml", "--out", "out", "--executor", "serial")
    assert code == 0 and "2 runs (2 already done)" in out


def test_more_seeds_and_values_extend_the_store(tmp_path):
    """The sweep block, the seed and output are not part of the scenario hash: they add trials."""
    first = run_sweep(scenario_from_dict(_data(), "s.yaml"), tmp_path, seeds=1, executor="serial")
    before = _by_id(first.table)
    grown = _data(sweep={"strategy.params.d0_m": [6.0, 9.0, 12.0]})
    second = run_sweep(scenario_from_dict(grown, "s.yaml"), tmp_path, seeds=2, executor="serial")
    after = _by_id(second.table)
    assert (second.n_runs, second.n_skipped) == (6, 2)
    assert set(before) < set(after)  # the old ids are kept as they were
    for trial_id, row in before.items():
        assert {k: v for k, v in row.items() if k not in TIMING} == {
            k: v for k, v in after[trial_id].items() if k not in TIMING
        }
    assert scenario_hash(_data()) == scenario_hash(grown)
    assert (tmp_path / STORE_FILE).is_file()


def test_the_status_table_is_one_parquet_file_for_any_tool(tmp_path):
    """Done and failed trials in one table; read with DuckDB when installed, else pyarrow."""
    import _flaky_strategy  # noqa: F401  (the "flaky" strategy)

    data = _data(sweep={"strategy.params.fail": [False, True]})
    data["strategy"] = {"name": "flaky", "params": {}}
    with pytest.raises(RuntimeError):
        run_sweep(scenario_from_dict(data, "f.yaml"), tmp_path, seeds=2, executor="serial")
    table = tmp_path / "sweep.parquet"
    try:
        import duckdb
    except ImportError:
        counts: dict[str, int] = {}
        for r in pq.read_table(table, columns=["status"]).to_pylist():
            counts[r["status"]] = counts.get(r["status"], 0) + 1
        failed_seeds = sorted(
            r["seed"] for r in pq.read_table(table).to_pylist() if r["status"] == "failed"
        )
    else:
        rows = duckdb.sql(f"SELECT status, count(*) FROM '{table}' GROUP BY status").fetchall()
        counts = dict(rows)
        query = f"SELECT seed FROM '{table}' WHERE status = 'failed' ORDER BY seed"
        failed_seeds = [s for (s,) in duckdb.sql(query).fetchall()]
    assert counts == {"done": 2, "failed": 2}
    assert failed_seeds == [1, 2]


def test_dask_local_cluster_gives_the_same_table_trial_by_trial(tmp_path):
    distributed = pytest.importorskip("distributed")
    scenario = scenario_from_dict(_data(steps=10), "s.yaml")
    local = _by_id(run_sweep(scenario, tmp_path / "local", seeds=2, executor="processes",
                             workers=2).table)  # fmt: skip
    with distributed.LocalCluster(
        n_workers=1,
        threads_per_worker=1,
        processes=False,
        dashboard_address=None,
        protocol="tcp://",
        host="127.0.0.1",
    ) as cluster:  # fmt: skip  (a worker thread, reached by its loopback address)
        dask = _by_id(run_sweep(scenario, tmp_path / "dask", seeds=2, executor="dask",
                                address=cluster.scheduler_address).table)  # fmt: skip
    assert sorted(local) == sorted(dask) and len(local) == 4
    for trial_id, row in local.items():
        same = {k: v for k, v in row.items() if k not in TIMING}
        assert same == {k: v for k, v in dask[trial_id].items() if k not in TIMING}, trial_id
        assert row["status"] == "done"
