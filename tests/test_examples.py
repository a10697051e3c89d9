"""The runnable examples keep working (they are the plug-in documentation)."""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import ModuleType

import numpy as np
import pyarrow.parquet as pq
import pytest

EXAMPLES_DIR = Path(__file__).parents[1] / "examples"
EXAMPLES = sorted(EXAMPLES_DIR.glob("*.py"))


def _load(path: Path) -> ModuleType:
    spec = importlib.util.spec_from_file_location(f"tether_example_{path.stem}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("path", EXAMPLES, ids=[p.stem for p in EXAMPLES])
def test_example_runs(path, tmp_path):
    summary = _load(path).main(str(tmp_path / path.stem))
    assert (tmp_path / path.stem / "summary.json").exists()
    assert summary["steps"] > 0


def test_custom_strategy_contracts_the_team(tmp_path):
    """The example controller is a rendezvous: the team's spread must shrink."""
    _load(EXAMPLES_DIR / "custom_strategy.py").main(str(tmp_path / "r"))
    robots = pq.read_table(tmp_path / "r" / "robots.parquet").to_pydict()
    step = np.asarray(robots["step"])
    xy = np.stack([robots["x_m"], robots["y_m"]], axis=1)
    spread = [xy[step == s].std(axis=0).sum() for s in (step.min(), step.max())]
    assert spread[1] < 0.5 * spread[0]
