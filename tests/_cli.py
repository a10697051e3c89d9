"""Run the ``tether`` command line in-process, as the tests of its commands do."""

from __future__ import annotations

import pytest

from tether import cli


def tether(capsys: pytest.CaptureFixture[str], *args: str) -> tuple[int, str, str]:
    """Exit code, standard output and standard error of ``tether ARGS``."""
    try:
        cli.main(list(args))
        code = 0
    except SystemExit as exc:
        code = int(exc.code or 0)
    captured = capsys.readouterr()
    return code, captured.out, captured.err
