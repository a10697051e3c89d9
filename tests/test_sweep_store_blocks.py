"""A sweep store refuses a scenario changed in any block that changes what a trial computes.

The blocks come from the schema (:class:`tether.config.Scenario`); every leaf field of
every hashed block, and every parameter of every built-in strategy, changes the
scenario hash. One real refusal per top-level block goes through ``open_store``; the
blocks left out of the hash are shown not to change a trial's results.
"""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import pytest

from _parameter_runs import SILENT, changed
from _parameters import STRATEGY_SCENARIOS, model_fields
from tether.config import Scenario, load_scenario, scenario_from_dict, set_dotted
from tether.errors import OutputError
from tether.experiments.store import UNHASHED, open_store, scenario_hash
from tether.plugins import BUILTINS
from tether.registry import STRATEGIES
from tether.runner import run

#: one valid change per top-level block (for the real refusal)
BLOCK_CHANGES: dict[str, dict[str, Any]] = {
    "name": {"name": "renamed"},
    "description": {"description": "another text"},
    "world": {"world__dim": 3},
    "team": {"team__n_robots": 7},
    "sensing": {"sensing__range_m": 14.0},
    "sim": {"sim__dt_s": 0.5},
    "strategy": {"strategy__params__gamma": 0.3},
}


def other(value: Any) -> Any:
    """A different value of the same JSON kind."""
    if isinstance(value, bool):
        return not value
    if isinstance(value, int | float):
        return value * 1.5 + 1
    if isinstance(value, str):
        return value + "x"
    if isinstance(value, list):
        return [*value, value[-1]] if value else [1.0]
    if isinstance(value, dict):
        return {**value, "x": 1}
    return 1.0  # None: set


def get_dotted(data: dict[str, Any], key: str) -> Any:
    node: Any = data
    for part in key.split("."):
        if not isinstance(node, dict) or part not in node:
            return None
        node = node[part]
    return node


def with_leaf(data: dict[str, Any], key: str) -> dict[str, Any]:
    out = copy.deepcopy(data)
    set_dotted(out, key, other(get_dotted(out, key)))
    return out


def test_every_top_level_block_is_hashed_or_shown_not_to_change_a_trial() -> None:
    assert set(Scenario.model_fields) == set(BLOCK_CHANGES) | set(UNHASHED)
    assert set(UNHASHED) == {"output", "seed", "sweep"}  # shown below not to change a trial


SCENARIO_LEAVES = [
    k for k in model_fields(Scenario) if k.split(".")[0] not in UNHASHED and k != "strategy.params"
]


@pytest.mark.parametrize("key", SCENARIO_LEAVES)
def test_a_changed_scenario_field_changes_the_hash(key: str) -> None:
    data = scenario_from_dict(SILENT).model_dump(mode="json")
    assert scenario_hash(with_leaf(data, key)) != scenario_hash(data), key


STRATEGY_LEAVES = [
    (name, key) for name in sorted(BUILTINS[STRATEGIES])
    for key in model_fields(STRATEGIES.get(name).Params)
]  # fmt: skip


@pytest.mark.parametrize(
    ("name", "key"), STRATEGY_LEAVES, ids=[f"{n}:{k}" for n, k in STRATEGY_LEAVES]
)
def test_a_changed_strategy_parameter_changes_the_hash(name: str, key: str) -> None:
    data = load_scenario(STRATEGY_SCENARIOS[name]).model_dump(mode="json")
    data["strategy"]["name"] = name
    assert scenario_hash(with_leaf(data, f"strategy.params.{key}")) != scenario_hash(data)


@pytest.mark.parametrize("block", sorted(BLOCK_CHANGES))
def test_the_store_refuses_a_change_in_each_block(block: str, tmp_path: Path) -> None:
    base = changed(SILENT, sweep={"strategy.params.d0_m": [6.0, 9.0]})
    out = open_store(scenario_from_dict(base), tmp_path / "sweep")
    stored = json.loads((out / "store.json").read_text())
    new = changed(base, **BLOCK_CHANGES[block])
    if block == "world":
        new["strategy"]["params"]["trajectory"]["waypoints"] = [[0, 0, 0], [60, 0, 0]]
    with pytest.raises(OutputError, match="holds the trials of another scenario"):
        open_store(scenario_from_dict(new), out)
    assert json.loads((out / "store.json").read_text()) == stored  # nothing rewritten
    open_store(scenario_from_dict(base), out)  # the same scenario resumes


@pytest.mark.parametrize(
    "change",
    [{"output__record_every": 4}, {"output__figures": True}, {"sweep": {"sim.dt_s": [1.0]}}],
    ids=["record_every", "figures", "sweep"],
)
def test_unhashed_blocks_do_not_change_a_trial(change: dict, tmp_path: Path) -> None:
    """``output`` and ``sweep`` change what is written and which trials run, not a trial's
    results (``seed`` names the trial: its run folder is ``seed-<s>``)."""
    base = changed(SILENT, sim__max_steps=8)
    a = run(base, out_dir=tmp_path / "a").summary
    b = run(changed(base, **change), out_dir=tmp_path / "b").summary
    for summary in (a, b):  # what measures the machine, not the trial
        summary.pop("wall_time_s")
        summary.pop("cpu_time_s")
        summary.pop("provenance")
    assert a == b
