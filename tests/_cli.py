"""Run the ``tether`` command line in-process, as the tests of its commands do."""

from __future__ import annotations

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
