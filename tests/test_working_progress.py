"""Work without a count shows what it does once it lasts: `validate`, `run` and `sweep`
before their first step or trial (building a world, placing a large team, checking a
sweep's combinations) -- a spinner on a terminal, plain lines elsewhere, nothing with
--quiet, and no thread left behind.

A slow build is stood in for by a world builder that waits until the command has said
what it is doing (bounded: a command that never says so fails the test, it does not hang).
"""

from __future__ import annotations

import re
import threading
from pathlib import Path

import pytest

from _cli import on_terminal, tether
from tether import cli, progress, runner
from tether.progress import Working

#: longest a stand-in build waits for the command's progress line
WAIT_S = 60.0


def test_a_line_while_the_work_lasts_and_none_for_short_work() -> None:
    said: list[str] = []
    shown = threading.Event()

    def say(line: str) -> None:
        said.append(line)
        shown.set()

    with Working("placing 300 robots", None, say, after_s=0.0, every_s=3600.0):
        assert shown.wait(WAIT_S)
    assert len(said) == 1 and re.fullmatch(r"placing 300 robots \.\.\. \(\d+ s\)", said[0])
    with Working("building the world", None, said.append, after_s=3600.0):
        pass  # ends long before it would be shown
    assert len(said) == 1
    assert not [t for t in threading.enumerate() if t.name == "tether-working"]


@pytest.fixture
def slow_build(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """The world builder waits for the command's first line of progress (returned list)."""
    lines: list[str] = []
    shown = threading.Event()
    say = cli.say

    def say_and_note(line: str) -> None:
        lines.append(line)
        if line.endswith(" s)"):
            shown.set()
        say(line)

    build_world = runner.build_world

    def waiting(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        shown.wait(WAIT_S)
        return build_world(*args, **kwargs)

    monkeypatch.setattr(progress, "AFTER_S", 0.0)
    monkeypatch.setattr(cli, "say", say_and_note)
    monkeypatch.setattr(runner, "build_world", waiting)
    return lines


@pytest.mark.parametrize(
    ("command", "line"),
    [
        (("validate", "silent_demo"), r"checking silent_demo: its world, 12 robots, strategy"),
        (("run", "silent_demo", "--no-figures", "--out", "{tmp}/r"),
         r"building the world and placing 12 robots"),
        (("sweep", "silent_demo", "--executor", "serial", "--out", "{tmp}/s"),
         r"checking every combination of the sweep"),
    ],
)  # fmt: skip
def test_commands_say_what_they_prepare_off_a_terminal(
    command, line, slow_build, capsys, tmp_path
) -> None:
    args = [a.format(tmp=tmp_path) for a in command]
    code, out, err = tether(capsys, *args, "--set", "sim.max_steps=3")
    assert code == 0, err
    assert re.search(line + r".* \.\.\. \(\d+ s\)", out), out
    assert not [t for t in threading.enumerate() if t.name == "tether-working"]


def test_quiet_says_nothing(monkeypatch, capsys, tmp_path) -> None:
    started: list[str] = []
    start = Working.start

    def noted(self: Working) -> Working:
        started.append(self.label)
        return start(self)

    monkeypatch.setattr(progress, "AFTER_S", 0.0)
    monkeypatch.setattr(Working, "start", noted)
    code, out, err = tether(capsys, "run", "silent_demo", "--set", "sim.max_steps=3",
                            "--no-figures", "--quiet", "--out", str(tmp_path / "r"))  # fmt: skip
    assert code == 0, err
    assert started == [] and " s)" not in out
    code, out, err = tether(capsys, "run", "silent_demo", "--set", "sim.max_steps=3",
                            "--no-figures", "--out", str(tmp_path / "v"))  # fmt: skip
    assert code == 0, err
    assert started == ["building the world and placing 12 robots"]  # the check can fail


SLOW_RUN = """
import sys, time
from tether import progress, runner
from tether.cli import main
build_world = runner.build_world
def slow(*args, **kwargs):
    time.sleep(3)
    return build_world(*args, **kwargs)
runner.build_world = slow
progress.AFTER_S = 0.0
sys.argv[0] = "tether"
main()
"""


def test_a_spinner_with_the_time_on_a_terminal(tmp_path: Path) -> None:
    """In a pseudo-terminal, as a user sees it: the spinner, no plain line."""
    args = ["run", "silent_demo", "--set", "sim.max_steps=3", "--no-figures", "--out", "r"]
    returncode, plain = on_terminal(SLOW_RUN, args, tmp_path)
    assert returncode == 0
    assert re.search(r"building the world and placing 12 robots \(\d+ s\)", plain), plain[-800:]
    assert "placing 12 robots ..." not in plain
    assert "results: r" in plain
