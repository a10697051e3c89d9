"""The command lines the reference pages show (```console blocks) print what the page says.

Each ``$ [VAR=value ...] tether ...`` line runs in an empty folder holding ``my_paths.py``
(the user's module of leader paths the pages name); its output, standard output then
standard error, is the lines that follow it on the page, exactly (but for the line a
command prints when its preparation lasts, on a busy machine).
"""

from __future__ import annotations

import os
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGES = sorted((ROOT / "docs" / "reference").glob("*.md"))
_BLOCK = re.compile(r"```console\n(.*?)```", re.DOTALL)
#: a line saying what a command is still doing (on a busy machine): not part of the page
_WORKING = re.compile(r" \.\.\. \(\d+ s\)$")


def _commands() -> list[tuple[str, str, list[str]]]:
    found = []
    for page in PAGES:
        for block in _BLOCK.findall(page.read_text()):
            for chunk in re.split(r"^\$ ", block, flags=re.MULTILINE)[1:]:
                command, *shown = chunk.rstrip("\n").split("\n")
                found.append((page.name, command, shown))
    return found


COMMANDS = _commands()


def test_the_reference_shows_commands() -> None:
    assert {page for page, _, _ in COMMANDS} >= {"errors.md"}


@pytest.mark.parametrize(("page", "command", "shown"), COMMANDS,
                         ids=[f"{p}:{c[:60]}" for p, c, _ in COMMANDS])  # fmt: skip
def test_a_shown_command_prints_what_the_page_shows(page, command, shown, tmp_path) -> None:
    shutil.copy(ROOT / "tests" / "user_leader_paths.py", tmp_path / "my_paths.py")
    words = shlex.split(command)
    env = dict(os.environ, TETHER_JIT="0", COLUMNS="200")
    env.pop("TETHER_MEMORY_LIMIT_GB", None)
    while "=" in words[0]:
        key, _, value = words.pop(0).partition("=")
        env[key] = value
    assert words[0] == "tether", command
    done = subprocess.run([sys.executable, "-m", "tether", *words[1:]], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=300)  # fmt: skip
    printed = [line for line in done.stdout.splitlines() + done.stderr.splitlines()
               if not _WORKING.search(line)]  # fmt: skip
    assert printed == shown, f"{page}: {command}\n{done.stdout}{done.stderr}"
