"""`tether report SWEEP_DIR`: report.md with figures, statistics of the trials, failures."""

from __future__ import annotations

import re
import statistics
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from _cli import tether as _tether
from tether.config import load_scenario, scenario_from_dict
from tether.experiments.sweep import run_sweep


@pytest.fixture(scope="module")
def sweep_dir(tmp_path_factory) -> Path:
    data = load_scenario("silent_demo").model_dump(mode="json")
    data["sim"]["max_steps"] = 8
    data["output"]["figures"] = False
    data["sweep"] = {"axes": {"team.n_robots": {"start": 6, "stop": 9, "step": 3}}, "seeds": 3}
    out = tmp_path_factory.mktemp("report") / "sweep"
    run_sweep(scenario_from_dict(data, "r.yaml"), out, executor="serial")
    return out


def test_report_has_figures_and_statistics_of_the_trials(sweep_dir, capsys):
    code, out, err = _tether(capsys, "report", str(sweep_dir))
    assert code == 0, err
    report = (sweep_dir / "report.md").read_text()
    assert f"report: {sweep_dir / 'report.md'}" in out
    assert "- trials: 6 (6 done, 0 failed)" in report
    images = re.findall(r"!\[[^]]*\]\(([^)]+)\)", report)
    assert "figures/bands_min_links_vs_n_robots.png" in images  # metric against team size
    assert "figures/time_links.png" in images  # links against time, bands over seeds
    assert all((sweep_dir / image).stat().st_size > 1000 for image in images)
    # the statistics are those of the table: recompute the means here, independently
    rows = pq.read_table(sweep_dir / "sweep.parquet").to_pylist()
    for n in (6, 9):
        links = [r["min_links"] for r in rows if r["param:team.n_robots"] == n]
        assert f"| n_robots={n} | 3 | {statistics.mean(links):.4g} |" in report
    section = report.split("### min_links", 1)[1].split("###", 1)[0]
    assert re.search(r"(Welch's t-test|Mann-Whitney U): statistic", section)
    assert "(chosen: " in section


def test_report_lists_failed_trials_with_seed_and_error(tmp_path, capsys):
    import _flaky_strategy  # noqa: F401  (the "flaky" strategy)

    data = load_scenario("silent_demo").model_dump(mode="json")
    data["sim"]["max_steps"] = 4
    data["output"]["figures"] = False
    data["strategy"] = {"name": "flaky", "params": {}}
    data["sweep"] = {"strategy.params.fail": [False, True]}
    with pytest.raises(RuntimeError):
        run_sweep(scenario_from_dict(data, "f.yaml"), tmp_path, seeds=2, executor="serial")
    code, _, err = _tether(capsys, "report", str(tmp_path))
    assert code == 0, err
    report = (tmp_path / "report.md").read_text()
    assert "- trials: 4 (2 done, 2 failed)" in report
    failed = re.findall(r"^\| `(fail=True~[0-9a-f]{8}/seed-\d)` \| (\d) \| internal error", report,
                        re.MULTILINE)  # fmt: skip
    assert sorted(seed for _, seed in failed) == ["1", "2"]


def test_report_of_a_folder_that_is_not_a_sweep_is_one_line(tmp_path, capsys):
    code, _, err = _tether(capsys, "report", str(tmp_path))
    assert code == 2
    [line] = err.strip().splitlines()
    assert line == (
        f"error: {tmp_path}: not a finished sweep folder (no sweep.parquet); run "
        f"`tether sweep SCENARIO --out {tmp_path}` first"
    )


def test_a_zip_group_is_named_and_plotted_by_its_first_axis():
    from tether.experiments.results import SweepResults

    sweep = {
        "axes": {"team.n_robots": [10, 15], "world.scene": ["empty", "town"],
                 "sensing.range_m": [6.0, 5.0]},
        "zip": [["world.scene", "sensing.range_m"]],
    }  # fmt: skip
    rows = [
        {"status": "done", "param:team.n_robots": n, "param:world.scene": s,
         "param:sensing.range_m": r, "m": float(n)}
        for n in (10, 15) for s, r in (("empty", 6.0), ("town", 5.0))
    ]  # fmt: skip
    axes = ["team.n_robots", "world.scene", "sensing.range_m"]
    results = SweepResults(Path("."), {"sweep": sweep}, rows, axes)
    assert results.shown_axes == ["team.n_robots", "world.scene"]
    assert results.numeric_axes() == ["team.n_robots"]  # not range_m: it moves with the scene
    assert results.label(rows[1]) == "n_robots=10,scene=town"
    # a first axis whose values repeat in the group cannot name the rows alone
    sweep["axes"]["world.scene"] = ["town", "town"]
    assert results.shown_axes == axes and "sensing.range_m" in results.numeric_axes()
