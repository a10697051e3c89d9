"""The documentation site builds with warnings as errors, its reference pages generated.

``mkdocs build --strict`` fails on a broken link or anchor, a page missing from the
navigation, a docstring the API reference cannot read, or a reference page that cannot
be generated. The build takes about ten seconds on a loaded 2-core machine.
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def site(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("site")
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}  # a notice of the theme, not of the docs
    proc = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--site-dir", str(out)],
        cwd=ROOT,
        env=env,
        capture_output=True,
        text=True,
        timeout=600,
    )
    problems = [line for line in proc.stderr.splitlines() if "WARNING" in line or "ERROR" in line]
    assert proc.returncode == 0, "mkdocs build --strict failed:\n" + "\n".join(
        problems or proc.stderr.splitlines()[-20:]
    )
    return out


def test_the_site_builds_strict(site):
    assert (site / "index.html").is_file()


def test_reference_pages_are_generated(site):
    scenario = (site / "reference" / "scenario" / "index.html").read_text()
    assert "strategy.params.d0_m" in scenario and "world.params.height_m" in scenario
    assert "tether sweep" in (site / "reference" / "cli" / "index.html").read_text()
    assert "connected_all_steps" in (site / "reference" / "summary" / "index.html").read_text()
    assert "target_reached" in (site / "reference" / "tables" / "index.html").read_text()
    api = (site / "reference" / "api" / "tether.runner" / "index.html").read_text()
    assert "build" in api and "Turn a scenario into world" in api
