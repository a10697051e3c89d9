"""The quick size of a sweep (``sweep.quick``): grammar, ``--quick`` and a store never mixed.

Bad quick entries give one line and exit 2, naming the file, the field and the fix.
"""

from __future__ import annotations

import json
from pathlib import Path

import pyarrow.parquet as pq
import pytest
import yaml

from _cli import tether as _tether
from tether.config import load_scenario
from tether.quicksize import load_scenario_at, quick_data
from tether.sweepspec import SweepError, parse_sweep, quick_block

#: a full sweep of 3 zipped values x 3 seeds whose quick size is 2 values x 1 seed
BLOCK = {
    "axes": {"strategy.params.d0_m": [5.0, 8.0, 11.0], "team.n_robots": [6, 8, 10]},
    "zip": [["strategy.params.d0_m", "team.n_robots"]],
    "seeds": 3,
    "quick": {
        "seeds": 1,
        "axes": {"strategy.params.d0_m": [5.0, 8.0], "team.n_robots": [6, 8]},
        "set": {"sim.max_steps": 3},
    },
}


def _write(tmp_path: Path, block: dict, name: str = "s.yaml") -> Path:
    data = load_scenario("silent_demo").model_dump(mode="json")
    data["sim"]["max_steps"] = 5
    data["output"]["figures"] = False
    data["sweep"] = block
    path = tmp_path / name
    path.write_text(yaml.safe_dump(data, sort_keys=False))
    return path


def _with_quick(**quick) -> dict:
    return {**BLOCK, "quick": quick}


# ----------------------------------------------------------------------------- grammar


def test_quick_block_replaces_axes_and_seeds_and_keeps_zip():
    spec = parse_sweep(BLOCK)
    assert spec.n_combinations == 3 and spec.seeds == 3
    assert spec.quick is not None and spec.quick.set == {"sim.max_steps": 3}
    small = parse_sweep(quick_block(BLOCK))
    assert small.quick is None and small.seeds == 1
    assert small.combinations() == [
        {"strategy.params.d0_m": 5.0, "team.n_robots": 6},
        {"strategy.params.d0_m": 8.0, "team.n_robots": 8},
    ]
    # axes the quick entry does not name keep their values; no quick seeds keep the block's
    crossed = {
        "axes": {"a.b": [1, 2, 3], "c.d": [4, 5]},
        "seeds": 7,
        "quick": {"axes": {"a.b": [1]}},
    }
    small = parse_sweep(quick_block(crossed))
    assert small.axes == {"a.b": [1], "c.d": [4, 5]} and small.seeds == 7


def test_quick_block_of_a_plain_form_and_of_seeds_only():
    plain = {"a.b": [1, 2, 3], "quick": {"axes": {"a.b": {"start": 1, "stop": 2, "step": 1}}}}
    assert parse_sweep(quick_block(plain)).axes == {"a.b": [1, 2]}
    assert quick_block({"seeds": 50, "quick": {"seeds": 2}}) == {"seeds": 2}


@pytest.mark.parametrize(
    ("quick", "field", "words"),
    [
        ({}, "sweep.quick", "a mapping of seeds, axes and set"),
        ({"seed": 2}, "sweep.quick.seed", "allowed: seeds, axes, set"),
        ({"seeds": 0}, "sweep.quick.seeds", ">= 1"),
        ({"axes": {"sensing.range_m": [3.0]}}, "sweep.quick.axes.sensing.range_m", "not an axis"),
        ({"axes": {"team.n_robots": []}}, "sweep.quick.axes.team.n_robots", "empty axis"),
        ({"axes": {"team.n_robots": [6]}}, "sweep.quick.axes", "equal lengths"),
        ({"set": {"team.n_robots": 4}}, "sweep.quick.set.team.n_robots", "quick.axes"),
        ({"set": {"sweep.seeds": 4}}, "sweep.quick.set.sweep.seeds", "cannot set the sweep"),
        ({"set": [1]}, "sweep.quick.set", "map dotted scenario keys"),
    ],
)
def test_malformed_quick_entries_name_the_field(quick, field, words):
    with pytest.raises(SweepError) as err:
        parse_sweep(_with_quick(**quick))
    assert err.value.field == field and words in err.value.message


def test_quick_without_a_quick_entry_is_refused_with_the_fix():
    with pytest.raises(SweepError, match="no quick size.*without --quick"):
        quick_block({"a.b": [1]})


# ------------------------------------------------------------------ scenario and CLI


def test_quick_data_sets_keys_renames_and_set_wins_last(tmp_path):
    path = _write(tmp_path, BLOCK)
    data = yaml.safe_load(path.read_text())
    small = quick_data(data, "s.yaml")
    assert small["sim"]["max_steps"] == 3 and small["name"] == "silent_demo-quick"
    assert "quick" not in small["sweep"] and data["sim"]["max_steps"] == 5  # input untouched
    sc = load_scenario_at(path, quick=True, overrides=["sim.max_steps=4"])
    assert sc.sim.max_steps == 4 and sc.source.endswith("(quick size)")
    assert load_scenario_at(path).sim.max_steps == 5  # the full size is unchanged


@pytest.mark.parametrize("quick_flag", [[], ["--quick"]])
def test_validate_accepts_both_sizes(tmp_path, capsys, quick_flag):
    path = _write(tmp_path, BLOCK)
    code, out, err = _tether(capsys, "validate", str(path), *quick_flag)
    assert code == 0, err
    combos = "2 combinations, quick size" if quick_flag else "3 combinations)"
    assert combos in out


@pytest.mark.parametrize(
    ("quick", "quick_flag", "words"),
    [
        ({"set": {"sim.max_steps": -5}}, [], "sweep.quick.set: sim.max_steps: Input should be"),
        ({"set": {"sim.max_stepz": 5}}, ["--quick"], "sweep.quick.set: sim.max_stepz: unknown key"),
        ({"axes": {"sensing.range_m": [3.0]}}, [], "sweep.quick.axes.sensing.range_m: not an axis"),
        # a quick axis value checked like the full axes, even without --quick
        (
            {"axes": {"strategy.params.d0_m": [-5.0, 8.0], "team.n_robots": [6, 8]}},
            [],
            "(quick size): sweep.strategy.params.d0_m: value",
        ),
    ],
)
def test_bad_quick_entries_are_one_line_exit_2(tmp_path, capsys, quick, quick_flag, words):
    path = _write(tmp_path, _with_quick(**quick), "bad.yaml")
    code, out, err = _tether(capsys, "validate", str(path), *quick_flag)
    assert code == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "bad.yaml" in lines[0] and words in lines[0], err


def test_quick_on_a_scenario_without_one_exits_2(capsys):
    code, _, err = _tether(capsys, "validate", "silent_paper", "--quick")
    assert code == 2 and "silent_paper: sweep.quick: the scenario has no quick size" in err


def test_sweep_quick_runs_the_quick_grid_in_its_own_folder(tmp_path, capsys, monkeypatch):
    path = _write(tmp_path, BLOCK)
    monkeypatch.chdir(tmp_path)
    code, out, err = _tether(capsys, "sweep", str(path), "--quick", "--executor", "serial")
    assert code == 0, err
    folder = tmp_path / "runs" / "sweep-quick"  # the default folder of the quick size
    table = pq.read_table(folder / "sweep.parquet").to_pylist()
    assert len(table) == 2 and {r["status"] for r in table} == {"done"}  # 2 values x 1 seed
    assert {r["param:team.n_robots"] for r in table} == {6, 8}
    assert {r["steps"] for r in table} == {3}  # quick.set applied
    assert not (tmp_path / "runs" / "sweep").exists()
    assert yaml.safe_load((folder / "sweep.yaml").read_text())["name"] == "silent_demo-quick"
    assert json.loads((folder / "store.json").read_text())["scenario_hash"]


@pytest.mark.parametrize("first_quick", [True, False])
def test_quick_and_full_trials_never_share_a_folder(tmp_path, capsys, first_quick):
    # even with no quick `set` (same steps, same axis values, same seed: the same trial ids)
    block = {"strategy.params.d0_m": [5.0, 8.0], "quick": {"axes": {"strategy.params.d0_m": [5.0]}}}
    path = _write(tmp_path, block)
    out_dir = str(tmp_path / "fig")
    flags = [["--quick"], []] if first_quick else [[], ["--quick"]]
    code, _, err = _tether(
        capsys, "sweep", str(path), "--out", out_dir, "--executor", "serial", *flags[0]
    )
    assert code == 0, err
    code, _, err = _tether(
        capsys, "sweep", str(path), "--out", out_dir, "--executor", "serial", *flags[1]
    )
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "holds the trials of another scenario" in err and "name:" in err and "-quick" in err
    assert len(pq.read_table(Path(out_dir) / "sweep.parquet")) == (1 if first_quick else 2)
