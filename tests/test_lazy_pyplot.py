"""A run without figures never imports ``matplotlib.pyplot`` (about half a second of
start-up, :func:`tether.viz.plots.pyplot`) nor matplotlib at all (the colour maps of
:mod:`tether.viz.style` are made on first use), and the same run with figures still
draws them.

Each case runs in a fresh interpreter, so modules imported by other tests do not hide
an eager import (a module-level ``import matplotlib.pyplot`` anywhere on the run path
fails it).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

CODE = """
import sys
from tether.config import load_scenario
from tether.experiments.sweep import run_sweep  # the campaign path imports it too
from tether.runner import run

sc = load_scenario(sys.argv[1])
sc.sim.max_steps = 4
run(sc, out_dir=sys.argv[2], figures=False)
print("pyplot after a run without figures:", "matplotlib.pyplot" in sys.modules)
print("matplotlib after a run without figures:", "matplotlib" in sys.modules)
run(sc, out_dir=sys.argv[3], figures=True)
print("pyplot after a run with figures:", "matplotlib.pyplot" in sys.modules)
"""


@pytest.mark.parametrize("name", ["recurrent_demo", "silent_demo", "multi_target_empty"])
def test_pyplot_is_imported_only_to_draw(name: str, tmp_path: Path) -> None:
    plain, drawn = tmp_path / "plain", tmp_path / "drawn"
    out = subprocess.run(
        [sys.executable, "-c", CODE, name, str(plain), str(drawn)],
        capture_output=True, text=True, timeout=300, check=False,
    )  # fmt: skip
    assert out.returncode == 0, out.stderr[-2000:]
    assert "pyplot after a run without figures: False" in out.stdout
    assert "matplotlib after a run without figures: False" in out.stdout  # colour maps too
    assert "pyplot after a run with figures: True" in out.stdout
    assert (plain / "summary.json").is_file() and not list(plain.rglob("*.png"))
    assert list(drawn.rglob("*.png")), "the run with figures wrote no figure"
