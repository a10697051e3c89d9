"""Size limits are checked before any work, and the refusal shows the memory estimate.

``team.n_robots: 1000000`` (the schema's maximum) was placing robots for minutes before
any memory check. Now a lower bound of what the run needs is checked before the world is
built or a robot placed; ``tether validate`` shows the estimate of a run that fits.
"""

from __future__ import annotations

import re

import pytest

from _cli import tether
from tether import runner
from tether.config import MAX_ROBOTS, MAX_STEPS, builtin_scenarios, load_scenario


@pytest.fixture
def no_work(monkeypatch):
    """A budget of 4 GiB on every machine, and a failure if any world or team is made."""
    monkeypatch.setenv("TETHER_MEMORY_LIMIT_GB", "4")

    def refuse(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        raise AssertionError("work started before the size check")

    monkeypatch.setattr(runner, "build_world", refuse)
    monkeypatch.setattr(runner, "_place_team", refuse)


@pytest.mark.parametrize("name", builtin_scenarios())
def test_the_largest_team_is_refused_before_any_work(name, capsys, no_work, tmp_path):
    args = ("--set", f"team.n_robots={MAX_ROBOTS}")
    code, _, err = tether(capsys, "validate", name, *args)
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "team.n_robots" in lines[0], err
    match = re.search(r"need at least ([\d.]+) GiB", lines[0])
    assert match and float(match.group(1)) > 4, lines[0]  # the estimate, above the budget
    assert "4.0 GiB allowed" in lines[0]
    code, _, err_run = tether(capsys, "run", name, *args, "--out", str(tmp_path / "o"))
    assert code == 2 and err_run == err  # run refuses the same, before any work
    assert not (tmp_path / "o").exists()


def test_too_many_steps_are_refused_before_any_work(capsys, no_work):
    code, _, err = tether(capsys, "validate", "silent_demo", "--set", f"sim.max_steps={MAX_STEPS}")
    assert code == 2 and "GiB" in err and len(err.strip().splitlines()) == 1, err


def memory_of(max_steps: int) -> float:
    data = load_scenario("silent_demo").model_dump(mode="json")
    data["sim"]["max_steps"] = max_steps
    return runner.build(data).memory_bytes


def test_validate_shows_the_estimate_of_a_run_that_fits(capsys):
    code, out, err = tether(capsys, "validate", "silent_demo")
    assert code == 0, err
    assert re.search(r"memory about [\d.]+ (KiB|MiB)", out), out
    assert memory_of(30_000) > 50 * memory_of(300)  # a hundred times the steps
