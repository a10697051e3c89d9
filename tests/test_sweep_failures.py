"""A sweep survives any failing trial: recorded with its error and seed, the others finish."""

from __future__ import annotations

import json
import re
from pathlib import Path

import pyarrow.parquet as pq
import pytest
import yaml

import _flaky_strategy  # noqa: F401  (registers the "flaky" strategy, also in forked workers)
from tether import cli
from tether.config import load_scenario, scenario_from_dict
from tether.errors import TetherError
from tether.experiments.executors import Trial, run_trial
from tether.experiments.sweep import TrialsFailed, run_sweep


def _flaky(sweep: dict) -> dict:
    data = load_scenario("silent_demo").model_dump(mode="json")
    data["sim"]["max_steps"] = 6
    data["output"]["figures"] = False
    data["strategy"] = {"name": "flaky", "params": {}}
    data["sweep"] = sweep
    return data


@pytest.mark.parametrize("executor", ["serial", "processes"])
def test_a_trial_failing_with_any_exception_is_recorded_and_the_rest_finish(tmp_path, executor):
    scenario = scenario_from_dict(_flaky({"strategy.params.fail": [True, False]}), "flaky.yaml")
    lines: list[str] = []
    with pytest.raises(TrialsFailed) as err:
        run_sweep(scenario, tmp_path, seeds=3, executor=executor, workers=2, progress=lines.append)
    message = str(err.value)
    assert "\n" not in message
    assert "RuntimeError: flaky strategy failed at step 2" in message
    assert "(seed " in message and "(and 2 more)" in message
    assert "Traceback" in (err.value.details or "")  # the traceback, for TETHER_DEBUG
    rows = pq.read_table(tmp_path / "sweep.parquet").to_pylist()
    assert len(rows) == 6  # every trial has a row, finished or failed
    failed = [r for r in rows if r["error"] is not None]
    done = [r for r in rows if r["error"] is None]
    assert sorted(r["seed"] for r in failed) == [1, 2, 3]
    assert all(r["param:strategy.params.fail"] is True for r in failed)
    assert all("RuntimeError: flaky strategy failed" in r["error"] for r in failed)
    assert all(not Path(r["run_dir"]).exists() for r in failed)  # no half-written folder
    assert sorted(r["seed"] for r in done) == [1, 2, 3]
    for r in done:
        assert r["param:strategy.params.fail"] is False
        summary = json.loads((Path(r["run_dir"]) / "summary.json").read_text())
        assert summary["steps"] == 6 and summary["seed"] == r["seed"]
    assert len(lines) == 6 and sum("failed: internal error RuntimeError" in m for m in lines) == 3


def test_run_trial_turns_any_exception_into_an_outcome(tmp_path):
    data = _flaky({})
    data.pop("sweep")
    data["strategy"]["params"] = {"fail": True}
    trial = Trial(data, "flaky.yaml", str(tmp_path), 7, str(tmp_path / "run"))
    outcome = run_trial(trial)
    assert outcome.summary is None and outcome.internal
    assert outcome.error == "internal error RuntimeError: flaky strategy failed at step 2"
    assert "_flaky_strategy.py" in outcome.details
    data["strategy"]["params"] = {"fail": False, "bogus": 1}
    outcome = run_trial(Trial(data, "flaky.yaml", str(tmp_path), 7, str(tmp_path / "run")))
    assert outcome.summary is None and not outcome.internal
    assert "strategy.params.bogus: unknown key" in outcome.error


def test_bad_input_in_one_trial_is_a_tether_error_after_the_table(tmp_path):
    """A trial refused as bad input while running makes the sweep exit 2, not 1."""
    data = _flaky({"strategy.params.fail": [False, True]})
    data["strategy"]["params"] = {"fail_with": "input"}
    with pytest.raises(TetherError, match="refused at step 2") as err:
        run_sweep(scenario_from_dict(data, "flaky.yaml"), tmp_path, seeds=1)
    assert not isinstance(err.value, TrialsFailed)
    rows = pq.read_table(tmp_path / "sweep.parquet").to_pylist()
    assert [(r["param:strategy.params.fail"], r["status"], r["seed"]) for r in rows] == [
        (False, "done", 1),
        (True, "failed", 1),
    ]


def test_cli_sweep_with_a_failing_trial_exits_1_with_one_line(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "s.yaml").write_text(
        yaml.safe_dump(_flaky({"strategy.params.fail": [False, True]}))
    )
    with pytest.raises(SystemExit) as ex:
        cli.main(["sweep", "s.yaml", "--out", "out", "--seeds", "2"])
    assert ex.value.code == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "internal error TrialsFailed" in err[0] and "TETHER_DEBUG" in err[0]
    assert len(pq.read_table(tmp_path / "out" / "sweep.parquet")) == 4


def test_progress_lines_are_printed_verbatim(tmp_path, capsys, monkeypatch):
    """Values such as [nan, 3] reach the terminal as written (no rich markup)."""
    monkeypatch.chdir(tmp_path)
    data = load_scenario("silent_demo").model_dump(mode="json")
    data["sim"]["max_steps"] = 2
    data["output"]["figures"] = False
    data["sweep"] = {"description": ["[nan, 3]", "[bold]b"]}
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(data))
    cli.main(["sweep", "s.yaml", "--out", "o[bold]ut"])  # a folder name with markup in it
    out = capsys.readouterr().out
    assert re.search(r"o\[bold\]ut/description=nan_3~[0-9a-f]{8}~[0-9a-f]{8}/seed-1 done", out)
    assert re.search(r"o\[bold\]ut/description=bold_b~[0-9a-f]{8}~[0-9a-f]{8}/seed-1 done", out)
    assert "[1/2]" in out and "[2/2]" in out


def test_long_or_unsafe_values_get_short_distinct_folders(tmp_path):
    """A 100-point waypoint list or a path with '/' as a sweep value: safe, distinct names."""
    from tether.experiments.sweep import trials_of

    data = load_scenario("silent_demo").model_dump(mode="json")
    data["sim"]["max_steps"] = 2
    data["output"]["figures"] = False
    zigzag = [[float(k), float(k % 2)] for k in range(100)]
    data["sweep"] = {
        "strategy.params.trajectory.waypoints": [zigzag, zigzag[:50]],
        "description": ["a/b", "a_b"],
    }
    scenario = scenario_from_dict(data, "long.yaml")
    folders = [Path(t.run_dir).parent.name for _, t in trials_of(scenario, tmp_path, 1)]
    assert len(set(folders)) == 4
    assert all(len(f.encode()) <= 200 and "/" not in f for f in folders)
    result = run_sweep(scenario, tmp_path, seeds=1)
    assert result.n_runs == 4
    made = [p.name for p in tmp_path.iterdir() if p.is_dir() and p.name != "figures"]
    assert sorted(made) == sorted(folders)


def test_values_of_mixed_types_keep_the_table_writable(tmp_path):
    data = _flaky({"strategy.params.fail_at_step": [5, "7"]})
    result = run_sweep(scenario_from_dict(data, "mixed.yaml"), tmp_path, seeds=1)
    rows = pq.read_table(result.table).to_pylist()
    # "7" validates to 7 (an int parameter): one type in the column, one value per id
    assert sorted(r["param:strategy.params.fail_at_step"] for r in rows) == [5, 7]
