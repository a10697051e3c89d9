"""Monte Carlo sweeps: grid x seeds, resumable, the same results on every executor."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pyarrow.parquet as pq
import pytest
import yaml

from tether.config import load_scenario, scenario_from_dict
from tether.errors import TetherError
from tether.experiments.sweep import run_sweep, trials_of

KEYS = ("connected_all_steps", "steps", "min_links", "min_lambda2", "collisions")


def _scenario(sweep: dict | None = None, **sensing):
    data = load_scenario("silent_demo").model_dump(mode="json")
    data["sim"]["max_steps"] = 25
    data["sensing"].update(sensing)
    data["sweep"] = sweep if sweep is not None else {"strategy.params.d0_m": [6.0, 9.0]}
    return scenario_from_dict(data, "sweep-test.yaml")


def _table(path: Path) -> list[dict]:
    rows = pq.read_table(path).to_pylist()
    return sorted(rows, key=lambda r: (r["param:strategy.params.d0_m"], r["seed"]))


def test_grid_times_seeds_in_a_stable_order(tmp_path):
    trials = trials_of(_scenario(), tmp_path, seeds=3)
    assert [(c["strategy.params.d0_m"], t.seed) for c, t in trials] == [
        (6.0, 1), (6.0, 2), (6.0, 3), (9.0, 1), (9.0, 2), (9.0, 3),
    ]  # fmt: skip
    assert len({t.run_dir for _, t in trials}) == 6
    assert all(t.scenario["strategy"]["params"]["d0_m"] == c["strategy.params.d0_m"]
               for c, t in trials)  # fmt: skip


def test_serial_and_processes_give_identical_results(tmp_path):
    a = run_sweep(_scenario(), tmp_path / "serial", seeds=2)
    b = run_sweep(_scenario(), tmp_path / "procs", seeds=2, executor="processes", workers=2)
    rows_a, rows_b = _table(a.table), _table(b.table)
    assert len(rows_a) == len(rows_b) == 4
    for ra, rb in zip(rows_a, rows_b, strict=True):
        assert {k: ra[k] for k in KEYS} == {k: rb[k] for k in KEYS}

    # different d0 give different motions (the grid value reached the strategy)
    def final_xy(row: dict) -> list:
        robots = pq.read_table(Path(row["run_dir"]) / "robots.parquet").to_pylist()
        last = max(r["step"] for r in robots)
        return [(r["x_m"], r["y_m"]) for r in robots if r["step"] == last]

    assert final_xy(rows_a[0]) != final_xy(rows_a[2])
    assert final_xy(rows_a[0]) == final_xy(rows_b[0])


def test_dask_scheduler_runs_the_same_trials(tmp_path):
    distributed = pytest.importorskip("distributed")
    serial = _table(run_sweep(_scenario(), tmp_path / "serial", seeds=2).table)
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
    ) as cluster:  # a real scheduler reached by its address, as on a cluster
        result = run_sweep(
            _scenario(),
            tmp_path / "dask",
            seeds=2,
            executor="dask",
            address=cluster.scheduler_address,
        )
    rows = _table(result.table)
    assert [{k: r[k] for k in KEYS} for r in rows] == [{k: r[k] for k in KEYS} for r in serial]
    assert all((Path(r["run_dir"]) / "robots.parquet").exists() for r in rows)


def test_resume_reuses_finished_trials(tmp_path):
    first = run_sweep(_scenario(), tmp_path, seeds=2)
    kept = Path(_table(first.table)[0]["run_dir"]) / "summary.json"
    stamp = kept.stat().st_mtime_ns
    redo = Path(_table(first.table)[3]["run_dir"])
    for f in redo.rglob("*"):
        if f.is_file():
            f.unlink()
    second = run_sweep(_scenario(), tmp_path, seeds=2)
    assert (second.n_runs, second.n_skipped) == (4, 3)
    assert kept.stat().st_mtime_ns == stamp
    assert (redo / "summary.json").exists()


def test_a_combination_that_cannot_start_is_refused_before_any_trial(tmp_path):
    """validate == sweep: a 3 m range cannot connect the demo team (8 m apart) -> one line."""
    scenario = _scenario({"sensing.range_m": [15.0, 3.0]})
    with pytest.raises(TetherError, match="not connected") as err:
        run_sweep(scenario, tmp_path / "out", seeds=2, executor="processes", workers=2)
    assert "sweep: combination range_m=3.0 (seed 1) is refused" in str(err.value)
    assert not (tmp_path / "out").exists()  # nothing run, nothing written


def test_cli_sweep_with_processes(tmp_path):
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(_scenario().model_dump(mode="json")))

    def tether(*args: str) -> subprocess.CompletedProcess:
        cmd = [sys.executable, "-m", "tether.cli", "sweep", str(path), "--out", "out", *args]
        return subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True, timeout=300)

    ok = tether("--seeds", "2", "--executor", "processes", "--workers", "2")
    assert ok.returncode == 0, ok.stderr
    out = tmp_path / "out"
    assert (out / "sweep.parquet").exists() and (out / "figures" / "links.png").exists()
    assert len(pq.read_table(out / "sweep.parquet")) == 4
    bad = tether("--executor", "spark")
    assert bad.returncode == 2
    assert bad.stderr.strip().splitlines() == [
        "error: unknown executor 'spark'; expected one of: dask, processes, serial"
    ]


def test_sweep_of_an_exploration_strategy_draws_explored_area(tmp_path):
    """`recurrent` runs record explored area and links (robots + BS): the sweep draws both."""
    data = load_scenario("recurrent_demo").model_dump(mode="json")
    data["sim"]["max_steps"] = 40
    data["sweep"] = {"strategy.params.theta": [1, 6]}
    result = run_sweep(scenario_from_dict(data, "recurrent-sweep.yaml"), tmp_path, seeds=1)
    assert [f.name for f in result.figures] == ["links.png", "explored.png"]
    rows = pq.read_table(result.table).to_pylist()
    assert sorted(r["param:strategy.params.theta"] for r in rows) == [1, 6]
    assert all(0 < r["final_explored_fraction"] <= 1 for r in rows)
