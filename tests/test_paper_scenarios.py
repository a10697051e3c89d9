"""Every paper campaign in ``scenarios/paper/`` validates at both sizes and is the paper's setting.

* every file has a quick size smaller than its full size, and both sizes pass the axis
  checks of ``tether validate``; at the quick size every combination builds;
* ``continuous_fig9.yaml`` (one zipped sweep) gives, trial by trial, the scenarios of the
  three per-scene files the running campaign reads; ``silent_fig5.yaml`` is
  ``silent_paper.yaml``; a setting that two recurrent campaigns share (theta = 12 with
  instantaneous planning, theta = 1 with the default relay binding) is one scenario in
  both, so ``tether report --paper recurrent`` may take it from either.

Cost: building the quick combinations of ``continuous_fig9.yaml`` builds the town and the
office (3-D scenes), the slowest part (about 15 s on a loaded 2-core machine).
"""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

from tether.config import load_scenario
from tether.experiments.plan import check_combinations, seeds_of, trial_scenario
from tether.quicksize import load_scenario_at
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
    "recurrent_relay_binding.yaml",
    "continuous_fig9.yaml",
    "continuous_estimator.yaml",  # multi_target on the decentralized estimator (App. A)
    "mission.yaml",
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


def _trials(name: str, **pick) -> list[dict]:
    """The computed scenarios of the combinations of paper file ``name`` with ``pick``'s values."""
    scenario = load_scenario(PAPER / name)
    combos = [c for c in parse_sweep(scenario.sweep).combinations()
              if all(c.get(f"strategy.params.{k}") == v for k, v in pick.items())]  # fmt: skip
    return [_computed(trial_scenario(scenario, c).model_dump(mode="json")) for c in combos]


def test_settings_shared_by_two_campaigns_are_one_scenario():
    """The paper report may take a shared setting from either campaign: same trials."""
    fig4 = _trials("recurrent_fig4.yaml", method="apx", count_planning_time=False)
    assert len(fig4) == 3 and fig4 == _trials("recurrent_fig5_6.yaml", theta=12)
    relay = _trials("recurrent_relay_binding.yaml", relay_binding="assigned")
    assert len(relay) == 3 and relay == _trials("recurrent_fig5_6.yaml", theta=1)
    frontiers = _trials("recurrent_relay_binding.yaml", relay_binding="frontiers")
    for a, b in zip(relay, frontiers, strict=True):  # one value apart
        a_params, b_params = a["strategy"]["params"], b["strategy"]["params"]
        assert {k for k in a_params if a_params[k] != b_params[k]} == {"relay_binding"}
    none = _trials("recurrent_fig5_6_utility.yaml", coordination="none")
    greedy = _trials("recurrent_fig5_6_utility.yaml", coordination="greedy")
    assert len(none) == len(greedy) == 3
    for name in FILES:  # every recurrent file runs 5 BS positions (seeds 0-4) per setting
        if name.startswith("recurrent"):
            assert seeds_of(load_scenario(PAPER / name)) == [0, 1, 2, 3, 4]


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
