"""The scenario fuzzer in the suite: mutated built-in scenarios and campaigns (``_fuzz.py``).

Every case goes through ``tether validate`` then ``tether run`` (a few steps): both refuse
with the same one ``error:`` line and exit code 2, or both succeed -- no traceback, no exit
code 1, no hang, no disagreement. A few dozen cases here (seconds); ``python
benchmarks/fuzz_scenarios.py`` runs thousands and prints the counts docs/robustness.md shows.
"""

from __future__ import annotations

from pathlib import Path

from hypothesis import HealthCheck, Phase, given, seed, settings

import _fuzz

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
