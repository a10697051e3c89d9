"""Every paper campaign in ``scenarios/paper/`` validates at both sizes and is the paper's setting.

* every file has a quick size smaller than its full size, and both sizes pass the axis
  checks of ``tether validate``; at the quick size every combination builds;
* ``continuous_fig9.yaml`` (one zipped sweep) gives, trial by trial, the scenarios of the
  three per-scene files the running campaign reads; ``silent_fig5.yaml`` is
  ``silent_paper.yaml``; the trials of ``python -m tether.recurrent.report`` are the
  recurrent files' combinations (it derives them from the files).

Cost: building the quick combinations of ``continuous_fig9.yaml`` builds the town and the
office (3-D scenes), the slowest part (about 15 s on a loaded 2-core machine).
"""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from tether.config import load_scenario, scenario_from_dict
from tether.experiments.plan import check_combinations, seeds_of, trial_scenario
from tether.quicksize import load_scenario_at
from tether.recurrent.report import trial_scenario as report_trial_scenario
from tether.recurrent.report_settings import run_dir, settings_table
from tether.runner import check_sweep, strategy_class
from tether.sweepspec import parse_sweep

ROOT = Path(__file__).resolve().parents[1]
PAPER = ROOT / "src" / "tether" / "scenarios" / "paper"
#: the per-column files of Fig. 9 (read by benchmarks/fig9.py; kept as they are)
PER_SCENE = ("continuous_fig9_empty", "continuous_fig9_town", "continuous_fig9_office")
FILES = sorted(p.name for p in PAPER.glob("*.yaml") if p.stem not in PER_SCENE)
#: the experiments of the three papers, one file each (Fig. 6 shares Fig. 5's runs)
EXPECTED = {
    "silent_fig5.yaml",
    "recurrent_fig4.yaml",
    "recurrent_fig5_6.yaml",
    "recurrent_fig5_6_utility.yaml",
    "continuous_fig9.yaml",
}
#: what the trials compute (name and description only label them)
_LABELS = ("name", "description", "sweep", "seed")


def _computed(data: dict) -> dict:
    return {k: v for k, v in data.items() if k not in _LABELS}


def _n_trials(scenario) -> int:
    spec = parse_sweep(scenario.sweep)
    return spec.n_combinations * len(seeds_of(scenario))


def test_every_paper_experiment_has_its_file():
    assert set(FILES) == EXPECTED


@pytest.mark.parametrize("name", FILES)
def test_both_sizes_pass_the_axis_checks_and_quick_is_smaller(
    name, monkeypatch, skip_without_shared_map
):
    monkeypatch.chdir(ROOT)  # the maps are ../shared/maps from the repository root
    full = load_scenario_at(PAPER / name)
    skip_without_shared_map(full)
    quick = load_scenario_at(PAPER / name, quick=True)
    assert parse_sweep(full.sweep).quick is not None, f"{name}: no quick size"
    assert quick.name == f"{full.name}-quick"
    for scenario in (full, quick):
        check_sweep(scenario, strategy_class(scenario))
    assert _n_trials(quick) < _n_trials(full)
    assert quick.sim.max_steps <= full.sim.max_steps


@pytest.mark.parametrize("name", FILES)
def test_every_quick_combination_builds(name, monkeypatch, skip_without_shared_map):
    monkeypatch.chdir(ROOT)
    quick = load_scenario_at(PAPER / name, quick=True)
    skip_without_shared_map(quick)
    assert check_combinations(quick) == parse_sweep(quick.sweep).n_combinations


def test_continuous_fig9_is_the_three_per_scene_files_trial_by_trial():
    combined = load_scenario(PAPER / "continuous_fig9.yaml")
    spec = parse_sweep(combined.sweep)
    assert spec.n_combinations * len(seeds_of(combined)) == 3 * 6 * 100  # the paper's 1,800
    by_scene: dict[str, list[dict]] = {}
    for combo in spec.combinations():
        by_scene.setdefault(combo["world.scene"], []).append(combo)
    assert sorted(by_scene) == ["empty", "office", "town"]
    for stem in PER_SCENE:
        column = load_scenario(PAPER / f"{stem}.yaml")
        sizes = parse_sweep(column.sweep).axes["team.n_robots"]
        combos = by_scene[column.world.scene]
        assert [c["team.n_robots"] for c in combos] == sizes
        for combo in combos:
            ours = trial_scenario(combined, combo).model_dump(mode="json")
            theirs = trial_scenario(column, {"team.n_robots": combo["team.n_robots"]})
            assert _computed(ours) == _computed(theirs.model_dump(mode="json")), stem
    assert combined.seed == 0 and seeds_of(combined) == list(range(100))


def test_silent_fig5_is_silent_paper():
    ours = load_scenario(PAPER / "silent_fig5.yaml")
    paper = load_scenario("silent_paper")
    assert _computed(ours.model_dump(mode="json")) == _computed(paper.model_dump(mode="json"))
    assert parse_sweep(ours.sweep).axes == parse_sweep(paper.sweep).axes
    assert ours.seed == paper.seed


def _report_scenarios(name: str, maps_dir: Path) -> dict[tuple[str, str], dict]:
    """The report's scenario of every (map, label) taken from paper file ``name``."""
    table = settings_table()
    return {
        (m, label): report_trial_scenario(maps_dir / f"{m}.png", setting, steps=900, n_robots=12)
        for m in ("grass", "offices", "open")
        for label, setting in table.items()
        if setting.file == Path(name).stem
    }


@pytest.mark.parametrize(
    "name", ["recurrent_fig4.yaml", "recurrent_fig5_6.yaml", "recurrent_fig5_6_utility.yaml"]
)
def test_the_report_trials_are_the_paper_combinations(name, monkeypatch, skip_without_shared_map):
    """Each combination of the file is one report setting per map, value for value.

    The report's own labels (no variant) are exactly the file's combinations; the
    report only names them ``recurrent-report-<map>`` and gives the map's absolute path.
    """
    monkeypatch.chdir(ROOT)
    scenario = load_scenario(PAPER / name)
    skip_without_shared_map(scenario)
    spec = parse_sweep(scenario.sweep)
    assert seeds_of(scenario) == [0, 1, 2, 3, 4]  # the report's runs 0..4 (the BS position)
    maps = [Path(p).stem for p in spec.axes["world.params.path"]]
    assert maps == ["grass", "offices", "open"]
    maps_dir = scenario.resolve_path(spec.axes["world.params.path"][0]).parent
    table = settings_table()
    report = _report_scenarios(name, maps_dir)
    own = {k: v for k, v in report.items() if not table[k[1]].variant}
    paper = []
    for combo in spec.combinations():
        data = trial_scenario(scenario, combo).model_dump(mode="json")
        path = data["world"]["params"]["path"]
        data["world"]["params"]["path"] = str(scenario.resolve_path(path).resolve())
        paper.append(_computed(data))
    ours = [_computed(scenario_from_dict(d, "report", ROOT).model_dump(mode="json"))
            for d in own.values()]  # fmt: skip
    assert len(ours) == len(paper) == spec.n_combinations
    assert all(p in ours for p in paper) and all(o in paper for o in ours)
    for (m, _), data in report.items():
        assert data["name"] == f"recurrent-report-{m}" and data["seed"] == scenario.seed


def test_variants_change_one_value_and_same_runs_are_same_scenarios(
    monkeypatch, skip_without_shared_map
):
    """``theta1_frontiers`` and ``utility_none`` are theta1 and utility with one value changed;
    labels share a run folder exactly when their scenarios are equal."""
    monkeypatch.chdir(ROOT)
    scenario = load_scenario(PAPER / "recurrent_fig5_6.yaml")
    skip_without_shared_map(scenario)
    maps_dir = scenario.resolve_path(scenario.world.params["path"]).parent
    table = settings_table()
    report = {}
    for name in ("recurrent_fig4.yaml", "recurrent_fig5_6.yaml", "recurrent_fig5_6_utility.yaml"):
        report.update({k[1]: v for k, v in _report_scenarios(name, maps_dir).items()
                       if k[0] == "grass"})  # fmt: skip
    assert set(report) == set(table)
    for label, base in (("theta1_frontiers", "theta1"), ("utility_none", "utility")):
        a, b = report[label]["strategy"]["params"], report[base]["strategy"]["params"]
        assert {k for k in a if a[k] != b[k]} == {k.split(".")[-1] for k in table[label].variant}
    for a in table:
        for b in table:
            same_folder = run_dir(Path("o"), "m", a, 0) == run_dir(Path("o"), "m", b, 0)
            assert same_folder == (report[a] == report[b]), (a, b)


def test_package_data_ships_the_paper_files():
    text = (ROOT / "pyproject.toml").read_text()
    assert '"scenarios/paper/*.yaml"' in text
    for name in FILES:
        assert yaml.safe_load((PAPER / name).read_text())["sweep"]["quick"]


def test_campaigns_load_by_name_from_any_folder(tmp_path, monkeypatch):
    """``paper/<name>`` reaches the shipped file from anywhere (a pip-installed user has
    no ``scenarios/`` folder), and ``tether list`` names every campaign."""
    from tether.config import paper_campaigns

    monkeypatch.chdir(tmp_path)
    assert set(paper_campaigns()) == {f"paper/{p.stem}" for p in PAPER.glob("*.yaml")}
    by_name = load_scenario("paper/silent_fig5")
    by_path = load_scenario(PAPER / "silent_fig5.yaml")
    assert by_name.model_dump() == by_path.model_dump()
    with pytest.raises(Exception, match="paper/nope: file not found"):
        load_scenario("paper/nope")
