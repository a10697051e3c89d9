"""The ``sweep:`` grammar: lists and ranges, crossed or zipped axes, seeds, paired trials.

Bad sweep files give one line and exit 2 in ``validate`` and ``sweep`` alike.
"""

from __future__ import annotations

from pathlib import Path

import pyarrow.parquet as pq
import pytest
import yaml

from _cli import tether as _tether
from tether.config import load_scenario, scenario_from_dict
from tether.experiments.plan import combo_id, trials_of
from tether.sweepspec import SweepError, canonical, combo_hash, expand_range, parse_sweep


def _data(sweep: dict, steps: int = 4) -> dict:
    data = load_scenario("silent_demo").model_dump(mode="json")
    data["sim"]["max_steps"] = steps
    data["output"]["figures"] = False
    data["sweep"] = sweep
    return data


# ----------------------------------------------------------------------------- parsing


def test_plain_form_is_crossed_in_file_order():
    spec = parse_sweep({"team.n_robots": [10, 15], "strategy.params.d0_m": [5.0, 8.0, 11.0]})
    assert spec.seeds is None and spec.n_combinations == 6
    combos = spec.combinations()
    assert combos[:3] == [
        {"team.n_robots": 10, "strategy.params.d0_m": 5.0},
        {"team.n_robots": 10, "strategy.params.d0_m": 8.0},
        {"team.n_robots": 10, "strategy.params.d0_m": 11.0},
    ]
    assert combos[-1] == {"team.n_robots": 15, "strategy.params.d0_m": 11.0}


@pytest.mark.parametrize(
    ("spec", "expect"),
    [
        ({"start": 10, "stop": 35, "step": 5}, [10, 15, 20, 25, 30, 35]),  # both ends included
        ({"start": 10, "stop": 34, "step": 5}, [10, 15, 20, 25, 30]),  # stop off the grid
        ({"start": 0.1, "stop": 0.3, "step": 0.1}, [0.1, 0.2, 0.3]),  # no 0.30000000000000004
        ({"start": 0, "stop": 1, "num": 5}, [0.0, 0.25, 0.5, 0.75, 1.0]),
        ({"start": 7, "stop": 7, "step": 1}, [7]),
    ],
)
def test_ranges(spec, expect):
    values = expand_range("sweep.x", spec)
    assert values == expect
    assert all(type(v) is type(e) for v, e in zip(values, expect, strict=True))


def test_zip_moves_axes_together_and_crosses_the_rest():
    spec = parse_sweep(
        {
            "axes": {
                "team.n_robots": {"start": 10, "stop": 20, "step": 5},
                "strategy.params.d0_m": [5.0, 8.0],
                "sensing.range_m": [12.0, 14.0, 16.0],
            },
            "zip": [["team.n_robots", "sensing.range_m"]],
            "seeds": [3, 9],
        }
    )
    assert spec.groups == [("team.n_robots", "sensing.range_m"), ("strategy.params.d0_m",)]
    pairs = {(c["team.n_robots"], c["sensing.range_m"]) for c in spec.combinations()}
    assert pairs == {(10, 12.0), (15, 14.0), (20, 16.0)}  # zipped, never (10, 16.0)
    assert spec.n_combinations == len(spec.combinations()) == 6
    assert spec.seed_list(base_seed=0) == [3, 9]
    assert spec.seed_list(base_seed=0, override=2) == [0, 1]  # --seeds wins


@pytest.mark.parametrize(
    ("block", "field", "words"),
    [
        ({"sensing.range_m": []}, "sweep.sensing.range_m", "empty axis"),
        ({"axes": {"a.b": [1, 2], "c.d": [1]}, "zip": [["a.b", "c.d"]]}, "sweep.zip", "equal"),
        ({"axes": {"a.b": [1, 2]}, "zip": [["a.b", "x.y"]]}, "sweep.zip", "not an axis"),
        ({"axes": {"a.b": [1, 2]}, "zip": [[["a.b"], "a.b"]]}, "sweep.zip", "not an axis name"),
        ({"axes": {"a.b": [1, 2]}, "zip": [[{"a": 1}, "a.b"]]}, "sweep.zip", "not an axis name"),
        ({"a.b": {"start": 5, "stop": 1, "step": 1}}, "sweep.a.b", "below start"),
        ({"a.b": {"start": 1, "stop": 5}}, "sweep.a.b", "step or num"),
        ({"a.b": [1], "seeds": 0}, "sweep.seeds", ">= 1"),
        ({"axes": {"a.b": [1]}, "c.d": [2]}, "sweep.c.d", "beside 'axes'"),
    ],
)
def test_malformed_blocks_name_the_field(block, field, words):
    with pytest.raises(SweepError) as err:
        parse_sweep(block)
    assert err.value.field == field and words in err.value.message


# ----------------------------------------------------------------------- normalisation


def test_15_and_the_text_15_are_one_value_and_one_id():
    assert canonical("15.0") == canonical(15.0) == canonical(15) == 15
    assert combo_hash({"k": "15.0"}) == combo_hash({"k": 15})
    assert combo_hash({"k": 15.5}) != combo_hash({"k": 15})
    # a scenario given "15.0" as text runs the same trial, in the same folder, as 15.0
    a = scenario_from_dict(_data({"sensing.range_m": ["15.0", 20.0]}), "a.yaml")
    b = scenario_from_dict(_data({"sensing.range_m": [15.0, 20.0]}), "b.yaml")
    runs_a = [t.run_dir for _, t in trials_of(a, "out")]
    assert runs_a == [t.run_dir for _, t in trials_of(b, "out")]
    assert [c for c, _ in trials_of(a, "out")][0] == {"sensing.range_m": 15.0}


def test_trial_ids_are_short_readable_and_do_not_depend_on_axis_order():
    combo = {"team.n_robots": 15, "strategy.params.d0_m": 8.0}
    cid = combo_id(combo)
    assert cid.startswith("n_robots=15,d0_m=8.0~") and len(cid) < 40
    swapped = {"strategy.params.d0_m": 8.0, "team.n_robots": 15}
    assert cid.split("~")[1] == combo_id(swapped).split("~")[1]


# ----------------------------------------------------------------- validate and sweep


BAD_FILES = {
    "unknown axis": ({"sensing.rnage_m": [1.0]}, "sweep.sensing.rnage_m"),
    "empty axis": ({"sensing.range_m": []}, "sweep.sensing.range_m"),
    "mismatched zip lengths": (
        {
            "axes": {"sensing.range_m": [15.0, 16.0], "strategy.params.d0_m": [6.0, 8.0, 9.0]},
            "zip": [["sensing.range_m", "strategy.params.d0_m"]],
        },
        "sweep.zip",
    ),
    "a combination that cannot start": ({"sensing.range_m": [15.0, 3.0]}, "sweep"),
}


@pytest.mark.parametrize("name", list(BAD_FILES))
def test_bad_sweep_files_give_one_line_and_exit_2(name, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    block, field = BAD_FILES[name]
    Path("bad.yaml").write_text(yaml.safe_dump(_data(block)))
    lines = []
    for command in (["validate", "bad.yaml"], ["sweep", "bad.yaml", "--out", "sw"]):
        code, _, err = _tether(capsys, *command)
        assert code == 2, err
        [line] = err.strip().splitlines()
        assert line.startswith(f"error: bad.yaml: {field}") and "Traceback" not in line
        lines.append(line)
    assert lines[0] == lines[1]  # validate == sweep
    assert not Path("sw").exists()


def test_validate_builds_every_combination_so_zip_can_rescue_a_pair(tmp_path, capsys):
    """A 4 m range connects a team placed 3 m apart: zipped it validates, crossed it cannot."""
    axes = {"sensing.range_m": [15.0, 4.0], "team.init.spacing_m": [8.0, 3.0]}
    zipped = tmp_path / "zipped.yaml"
    zipped.write_text(yaml.safe_dump(_data({"axes": axes, "zip": [list(axes)]})))
    code, out, err = _tether(capsys, "validate", str(zipped))
    assert code == 0, err
    assert "sweep of 2 combinations" in out
    crossed = tmp_path / "crossed.yaml"
    crossed.write_text(yaml.safe_dump(_data(axes)))
    code, _, err = _tether(capsys, "validate", str(crossed))
    assert code == 2 and "combination range_m=4.0,spacing_m=8.0" in err


def test_seeds_of_the_block_and_the_paired_design(tmp_path):
    """One seed gives the same random initial team on every combination (paired trials)."""
    from tether.experiments.sweep import run_sweep

    data = _data({"axes": {"strategy.params.d0_m": [6.0, 9.0]}, "seeds": [4, 11]}, steps=3)
    result = run_sweep(scenario_from_dict(data, "paired.yaml"), tmp_path, executor="serial")
    rows = pq.read_table(result.table).to_pylist()
    assert sorted((r["param:strategy.params.d0_m"], r["seed"]) for r in rows) == [
        (6.0, 4), (6.0, 11), (9.0, 4), (9.0, 11),
    ]  # fmt: skip

    def start(row: dict) -> list:
        robots = pq.read_table(Path(row["run_dir"]) / "robots.parquet").to_pylist()
        return [(r["x_m"], r["y_m"]) for r in robots if r["step"] == 0]

    by = {(r["param:strategy.params.d0_m"], r["seed"]): start(r) for r in rows}
    assert by[(6.0, 4)] == by[(9.0, 4)]  # paired: same seed, same start on both axes values
    assert by[(6.0, 4)] != by[(6.0, 11)]  # another seed, another random start
