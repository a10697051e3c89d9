"""`tether run` shows its progress: a bar with the time left on a terminal, a plain line
every tenth of the way elsewhere, nothing with --quiet."""

from __future__ import annotations

import re
from pathlib import Path

from _cli import on_terminal, tether
from tether.progress import StepProgress
from tether.runner import run

STEPS = 50


def test_the_runner_reports_every_step(tmp_path) -> None:
    seen: list[int] = []
    out = run("silent_demo", out_dir=tmp_path / "r", figures=False, progress=seen.append)
    assert seen == list(range(out.summary["steps"] + 1))


def test_plain_lines_every_tenth_of_the_way() -> None:
    lines: list[str] = []
    progress = StepProgress(None, lines.append, 1000)
    for step in range(0, 1001, 7):  # steps as a run with an odd stride might report them
        progress(step)
    progress.stop()
    assert [int(re.search(r"\((\d+) %\)", s).group(1)) for s in lines] == list(range(10, 100, 10))
    assert all(re.fullmatch(r"step [\d,]+ of 1,000 \(\d+ %\)", s) for s in lines), lines


def test_run_prints_progress_lines_off_a_terminal_and_none_with_quiet(capsys, tmp_path) -> None:
    args = ["run", "silent_demo", "--set", f"sim.max_steps={STEPS}", "--no-figures"]
    code, out, _ = tether(capsys, *args, "--out", str(tmp_path / "a"))
    assert code == 0
    progress = [s for s in out.splitlines() if s.startswith("step ")]
    assert progress == [f"step {k} of {STEPS} ({100 * k // STEPS} %)" for k in range(5, 50, 5)]
    code, out, _ = tether(capsys, *args, "--quiet", "--out", str(tmp_path / "b"))
    assert code == 0
    assert not [s for s in out.splitlines() if s.startswith("step ")]
    assert "results:" in out


def test_run_draws_a_bar_with_the_time_left_on_a_terminal(tmp_path: Path) -> None:
    """In a pseudo-terminal, as a user sees it: the bar, no plain lines."""
    code = "import sys; from tether.cli import main; sys.argv[0] = 'tether'; main()"
    args = ["run", "silent_demo", "--set", "sim.max_steps=200", "--no-figures", "--out", "r"]
    returncode, plain = on_terminal(code, args, tmp_path)
    assert returncode == 0
    assert re.search(r"steps .*\d+/200 elapsed \d+:\d\d:\d\d left", plain), plain[-800:]
    assert "step 20 of 200" not in plain
    assert "results: r" in plain
