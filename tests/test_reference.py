"""The generated reference describes everything a user can set or read.

Every scenario key (the scenario, each built-in strategy, target generator and scene)
has a description; every summary key, Parquet column and event a built-in strategy
writes in a real run is described, and every described one without a condition is
written (no stale rows); every event kind and field the source emits is described;
every command and option of the command line has its help.
"""

from __future__ import annotations

import ast
import importlib
import json
from pathlib import Path

import pyarrow.parquet as pq
import pytest

from tether.config import apply_overrides, read_scenario_data, scenario_from_dict
from tether.plugins import BUILTINS
from tether.reference.cli import commands
from tether.reference.descriptions import KEY_DESCRIPTIONS
from tether.reference.outputs import (
    CORE_EVENTS,
    CORE_LINKS,
    CORE_ROBOTS,
    CORE_STEPS,
    CORE_SUMMARY,
    EVENTS,
)
from tether.reference.pages import reference_pages
from tether.reference.sections import scenario_sections
from tether.reference.strategy_outputs import STRATEGY_OUTPUTS
from tether.registry import STRATEGIES
from tether.runner import run

SRC = Path(__file__).resolve().parents[1] / "src" / "tether"

#: a short run of each built-in strategy (no data files needed)
RUNS = {
    "silent": "silent_demo",
    "connectivity": "connectivity_office",
    "multi_target": "multi_target_office",
    "recurrent": "recurrent_demo",
    "utility": "recurrent_utility",
    "unconstrained": "mission_unconstrained",
    "silent_exploration": "mission_silent",
    "continuous_exploration": "mission_continuous",
}


def test_every_scenario_key_has_a_description():
    sections = scenario_sections()
    titles = " ".join(s.title for s in sections)
    for registry, names in BUILTINS.items():
        if registry.kind != "link model":  # link models take no scenario keys of their own
            assert all(f"`{n}`" in titles for n in names), (registry.kind, names)
    missing = [f"{s.title}: {r.key}" for s in sections for r in s.rows if not r.description]
    assert not missing, "keys without a description:\n" + "\n".join(missing)
    assert sum(len(s.rows) for s in sections) > 200


def test_units_follow_the_key_names():
    rows = {r.key: r for s in scenario_sections() for r in s.rows}
    assert rows["sensing.range_m"].unit == "m"
    assert rows["sim.dt_s"].unit == "s"
    assert rows["strategy.params.kv_ns_per_m"].unit == "N s/m"
    assert rows["strategy.params.speed_m_s"].unit == "m/s"
    assert rows["sim.max_steps"].unit == ""
    assert rows["sensing.range_m"].default == "required"
    assert rows["sensing.range_m"].range == "> 0, <= 1e+07"


def test_each_table_description_names_an_undescribed_field():
    for path, text in KEY_DESCRIPTIONS.items():
        module, model, field = path.rsplit(".", 2)
        cls = getattr(importlib.import_module(module), model)
        assert field in cls.model_fields, f"{path}: no such field"
        assert not cls.model_fields[field].description, f"{path}: the field describes itself"
        assert text.strip(), path


@pytest.fixture(scope="module")
def runs(tmp_path_factory) -> dict[str, Path]:
    """One short run folder of each built-in strategy."""
    assert set(RUNS) == set(BUILTINS[STRATEGIES]), "give every built-in strategy a run here"
    out = {}
    for strategy, name in RUNS.items():
        data, label, base = read_scenario_data(name)
        data = apply_overrides(data, ["sim.max_steps=25"], label)
        folder = tmp_path_factory.mktemp(strategy) / "run"
        run(scenario_from_dict(data, label, base), out_dir=folder, figures=False)
        out[strategy] = folder
    return out


def _check(written: set[str], described: dict, what: str) -> None:
    undescribed = written - set(described)
    assert not undescribed, f"{what}: written but not described: {sorted(undescribed)}"
    stale = {k for k, o in described.items() if not o.when} - written
    assert not stale, f"{what}: described as always written but not written: {sorted(stale)}"


@pytest.mark.parametrize("strategy", list(RUNS))
def test_every_output_of_a_run_is_described(runs, strategy):
    folder, own = runs[strategy], STRATEGY_OUTPUTS[strategy]
    summary = json.loads((folder / "summary.json").read_text())
    _check(set(summary), {**CORE_SUMMARY, **own.summary}, f"{strategy} summary.json")
    steps = set(pq.read_schema(folder / "steps.parquet").names)
    _check(steps, {**CORE_STEPS, **own.steps}, f"{strategy} steps.parquet")
    robots = set(pq.read_schema(folder / "robots.parquet").names)
    robots_described = {**CORE_ROBOTS, **own.robots}
    assert robots <= set(robots_described), robots - set(robots_described)
    assert set(pq.read_schema(folder / "links.parquet").names) == set(CORE_LINKS)
    for event in pq.read_table(folder / "events.parquet").to_pylist():
        kind = event["kind"]
        assert kind in EVENTS and strategy in EVENTS[kind].strategies, (strategy, kind)
        fields = {k for k, v in event.items() if v is not None} - set(CORE_EVENTS)
        assert fields <= set(EVENTS[kind].fields), (kind, fields - set(EVENTS[kind].fields))


def _emitted() -> dict[str, set[str]]:
    """Every ``emit("kind", ..., field=...)`` / ``log("kind", field=...)`` in the source."""
    out: dict[str, set[str]] = {}
    for path in SRC.rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if (
                isinstance(node, ast.Call)
                and isinstance(node.func, ast.Attribute)
                and node.func.attr in ("emit", "log")
                and node.args
                and isinstance(node.args[0], ast.Constant)
                and isinstance(node.args[0].value, str)
            ):
                fields = {k.arg for k in node.keywords if k.arg is not None}
                out.setdefault(node.args[0].value, set()).update(fields)
    return out


def test_every_event_the_source_emits_is_described():
    emitted = _emitted()
    assert {"plan", "role", "target_reached"} <= set(emitted)
    for kind, fields in emitted.items():
        assert kind in EVENTS, f"event {kind!r} is not described"
        extra = fields - set(EVENTS[kind].fields) - set(CORE_EVENTS)
        assert not extra, f"event {kind!r}: fields {sorted(extra)} are not described"
    assert all(e.description for e in EVENTS.values())


def test_every_command_and_option_has_help():
    docs = commands()
    assert {c.name for c in docs} >= {"run", "validate", "sweep", "report", "list", "view"}
    for command in docs:
        assert command.help.strip(), command.name
        for option in command.options:
            assert option.help.strip(), f"tether {command.name} {option.names}: no help"


def test_the_pages_name_every_key():
    pages = reference_pages()
    scenario, summary = pages["reference/scenario.md"], pages["reference/summary.md"]
    for row in (r for s in scenario_sections() for r in s.rows):
        assert f"`{row.key}`" in scenario
    for key in [*CORE_SUMMARY, *(k for o in STRATEGY_OUTPUTS.values() for k in o.summary)]:
        assert f"`{key}`" in summary
    assert all(f"## `tether {c.name}`" in pages["reference/cli.md"] for c in commands())
