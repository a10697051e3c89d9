"""The scenario fuzzer in the suite: mutated built-in scenarios and campaigns (``_fuzz.py``).

Every case goes through ``tether validate`` then ``tether run`` (a few steps): both refuse
with the same one ``error:`` line and exit code 2, or both succeed -- no traceback, no exit
code 1, no hang, no disagreement. A few dozen cases here (seconds); ``python
benchmarks/fuzz_scenarios.py`` runs thousands and prints the counts docs/robustness.md shows.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, Phase, given, seed, settings

import _fuzz
from tether.config import read_scenario_data

ROOT = Path(__file__).resolve().parents[1]


def test_mutated_scenarios_are_refused_in_one_line_or_run(tmp_path):
    failures: list[str] = []

    @seed(0)  # the same cases on every run: a failure here is reproducible
    @settings(max_examples=30, deadline=None, database=None, phases=[Phase.generate],
              suppress_health_check=list(HealthCheck))  # fmt: skip
    @given(_fuzz.cases())
    def check(case: tuple[str, str, list[str]]) -> None:
        name, text, described = case
        kind, validate, run = _fuzz.check_case(text, tmp_path)
        if kind not in ("refused", "ran"):
            shown = (run or validate).err.strip()[-300:]
            failures.append(f"{kind}: {name} {described}: {shown}")

    with _fuzz.fuzz_environment(ROOT):
        check()
    assert failures == []


def _case(name: str, mutate, edits: list[str] = ()) -> str:  # noqa: ANN001
    """The YAML text of built-in ``name`` mutated by ``mutate(data)``, as the fuzzer writes it."""
    data, _, _ = read_scenario_data(name)
    mutate(data)
    return _fuzz.render(data, list(edits))


def _set_in_a_zip(data: dict) -> None:
    data["sweep"]["zip"][0][1] = _fuzz._TAG_SENTINEL


def _robots_as_many_as_steps(data: dict) -> None:
    steps = data["sim"]["max_steps"]  # 12,000: one object, written as an anchor and aliases
    data["team"]["n_robots"] = data["sweep"]["team.n_robots"][2] = steps
    data["sweep"]["team.n_robots"][3] = _fuzz._TAG_SENTINEL


def _list_in_a_zip(data: dict) -> None:
    data["sweep"]["zip"][0][0] = data["sweep"]["axes"]["strategy.params.coordination"]
    del data["world"]["dim"]


@pytest.mark.parametrize(
    ("name", "mutate", "edits", "needle"),
    [
        # exit code 1 (TypeError: unhashable type: 'list') from the sweep grammar
        ("paper/recurrent_fig5_6_utility", _list_in_a_zip, [], "is not an axis name"),
        # exit code 1 (TypeError: unhashable type: 'set') from the sweep grammar
        ("paper/continuous_fig9", _set_in_a_zip, ["tag:!!set {a: null}"], "tag !!set"),
        # a hang: 12,000 robots placed in the 50 x 70 x 10 m box for hours
        ("paper/continuous_fig9_empty", _robots_as_many_as_steps, ["tag:!!float '1e3'"],
         "12000 robots do not fit"),
    ],
)  # fmt: skip
def test_the_cases_the_benchmark_found_are_refused_in_one_line(
    name, mutate, edits, needle, tmp_path
) -> None:
    """The failures of an earlier ``benchmarks/fuzz_scenarios.py --cases 2500 --seed 0``."""
    text = _case(name, mutate, edits)
    with _fuzz.fuzz_environment(ROOT):
        kind, validate, run = _fuzz.check_case(text, tmp_path)
    assert kind == "refused", (kind, validate.err, run and run.err)
    assert needle in validate.err


def test_the_docs_show_the_benchmark_table() -> None:
    """docs/reference/robustness.md holds what ``fuzz_scenarios.py --table`` prints."""
    table = subprocess.run(
        [sys.executable, str(ROOT / "benchmarks" / "fuzz_scenarios.py"), "--table"],
        capture_output=True, text=True, check=True, timeout=120,
    ).stdout.strip()  # fmt: skip
    assert table and table in (ROOT / "docs" / "reference" / "robustness.md").read_text()
