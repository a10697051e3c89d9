"""The mission's paradigms on a small office floor: each measured, each as promised."""

from __future__ import annotations

import json

import pytest

from tether.config import apply_overrides, read_scenario_data, scenario_from_dict
from tether.errors import ScenarioError
from tether.runner import build, run

SMALL = ["world.params.size_m=[12.0, 14.0]", "team.n_robots=4"]


def mission(name: str, tmp_path, *sets: str) -> dict:
    data, label, base = read_scenario_data(name)
    data = apply_overrides(data, [*SMALL, *sets], label)
    out = tmp_path / name
    run(scenario_from_dict(data, label, base), out_dir=out, figures=False)
    return json.loads((out / "summary.json").read_text())


def test_unconstrained_reaches_the_goal_and_stops(tmp_path) -> None:
    s = mission("mission_unconstrained", tmp_path, "strategy.params.coverage_goal=0.5")
    m = s["mission"]
    assert m["coverage_goal_reached"] and m["stop_reason"] == "coverage goal"
    assert s["steps"] < 300
    assert m["base_explored_final"] >= 0.5 > s["mission"]["base_explored_final"] - 0.2
    assert m["base_time_to_50pct_s"] == s["steps"]  # stopped the step it got there


def test_silent_team_stays_connected_and_explores(tmp_path) -> None:
    # links by distance only (walls ignored): the setting of the steering law's theorem
    s = mission("mission_silent", tmp_path, "sim.max_steps=60", "strategy.params.link_model=disk")
    m = s["mission"]
    assert m["team_connected_frac"] == 1.0  # the paradigm's promise, measured
    assert m["team_explored_final"] > 0.2
    assert m["path_length_m"][s["leader"]] > 10.0  # the leader explores
    assert m["stop_reason"] == "time limit"


@pytest.mark.parametrize(
    ("sets", "field"),
    [
        (["strategy.params.d0_m=20"], "strategy.params.d0_m"),
        (["strategy.params.link_model=signal"], "strategy.params.link_model"),
        (["strategy.params.leader=9"], "strategy.params.leader"),
    ],
)
def test_silent_refuses_what_it_cannot_run(sets, field) -> None:
    data, label, base = read_scenario_data("mission_silent")
    data = apply_overrides(data, [*SMALL, *sets], label)
    with pytest.raises(ScenarioError, match=field):
        build(scenario_from_dict(data, label, base))
