"""Progress of a sweep: a rich bar (done, failed, time left) on a terminal, lines elsewhere."""

from __future__ import annotations

import io

import pytest
from rich.console import Console

import _flaky_strategy  # noqa: F401  (the "flaky" strategy)
from tether.config import load_scenario, scenario_from_dict
from tether.experiments.progress import LineProgress, RichProgress, progress_for
from tether.experiments.sweep import run_sweep


def _flaky_scenario():
    data = load_scenario("silent_demo").model_dump(mode="json")
    data["sim"]["max_steps"] = 4
    data["output"]["figures"] = False
    data["strategy"] = {"name": "flaky", "params": {}}
    data["sweep"] = {"strategy.params.fail": [False, True]}
    return scenario_from_dict(data, "f.yaml")


def test_the_bar_on_a_terminal_counts_done_and_failed(tmp_path):
    screen = io.StringIO()
    console = Console(file=screen, force_terminal=True, width=120)
    reporter = progress_for(console, print)
    assert isinstance(reporter, RichProgress)
    with pytest.raises(RuntimeError):
        run_sweep(_flaky_scenario(), tmp_path, seeds=2, executor="serial", progress=reporter)
    text = screen.getvalue()
    assert "4/4" in text and "2 failed" in text and "left" in text
    assert text.count("failed: ") == 2  # each failure printed once above the bar, with its seed
    assert "(seed 1)" in text and "(seed 2)" in text


def test_plain_lines_elsewhere(tmp_path):
    console = Console(file=io.StringIO(), force_terminal=False)
    lines: list[str] = []
    reporter = progress_for(console, lines.append)
    assert isinstance(reporter, LineProgress)
    with pytest.raises(RuntimeError):
        run_sweep(_flaky_scenario(), tmp_path, seeds=2, executor="serial", progress=reporter)
    assert [line.split(" ", 1)[0] for line in lines] == ["[1/4]", "[2/4]", "[3/4]", "[4/4]"]
    assert sum(" failed: internal error RuntimeError" in line for line in lines) == 2
