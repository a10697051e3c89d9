"""Run the ``tether`` command line in-process, as the tests of its commands do."""

from __future__ import annotations

import os
import pty
import re
import subprocess
import sys
from pathlib import Path

import pytest

from tether import cli


def tether(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    """Exit code, standard output and standard error of ``tether ARGS`` (only its own)."""
    capsys.readouterr()
    try:
        cli.main(list(args))
        code = 0
    except SystemExit as exc:  # sys.exit(None) is 0; a message instead of a code is 1
        code = 0 if exc.code is None else exc.code if isinstance(exc.code, int) else 1
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def one_error_line(code: int, err: str, *needles: str, max_length: int | None = None) -> str:
    """The one ``error:`` line of a refusal (exit code 2, no traceback, no internal error)
    that holds every needle; fails the test otherwise."""
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), err
    assert "internal error" not in lines[0] and "Traceback" not in err, err
    if max_length is not None:
        assert len(lines[0]) <= max_length, lines[0]
    for needle in needles:
        assert needle in lines[0], f"{needle!r} not in {lines[0]!r}"
    return lines[0]


def listed(out: str) -> dict[str, list[str]]:
    """``tether list``'s sections (``strategies``, ``scenes``, ...) and the names in each."""
    sections: dict[str, list[str]] = {}
    current = None
    for line in out.splitlines():
        if line and not line.startswith(" ") and line.rstrip().endswith(":"):
            current = line.split(" (", 1)[0].rstrip(":").strip()
            sections[current] = []
        elif line.startswith("  ") and current is not None and line.strip():
            sections[current].append(line.split()[0])
    return sections


def on_terminal(code: str, args: list[str], cwd: Path) -> tuple[int, str]:
    """Exit code and screen text (colours and cursor moves removed) of ``python -c CODE
    ARGS`` run in a pseudo-terminal, as a user sees a command."""
    parent, child = pty.openpty()
    env = dict(os.environ, TERM="xterm", COLUMNS="120", TETHER_JIT="0")
    proc = subprocess.Popen([sys.executable, "-c", code, *args], cwd=cwd, env=env,
                            stdin=child, stdout=child, stderr=child)  # fmt: skip
    os.close(child)
    chunks = []
    while True:
        try:
            data = os.read(parent, 4096)
        except OSError:  # the terminal closed: the command ended
            break
        if not data:
            break
        chunks.append(data)
    os.close(parent)
    code_ = proc.wait(timeout=120)
    screen = b"".join(chunks).decode(errors="replace")
    return code_, re.sub(r"\x1b\[[0-9;?]*[a-zA-Z]", "", screen)
