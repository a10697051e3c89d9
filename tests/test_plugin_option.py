"""`--plugin MODULE_OR_FILE` imports the user's own module before the scenario is read.

The example strategy (``examples/custom_strategy.py``, ``centroid_pull``) runs from its
YAML with ``--plugin``, is refused without it, runs in sweep trials of other processes
(which import the plug-in again), and every problem with a plug-in is one line.
"""

from __future__ import annotations

import json
import multiprocessing
import sys
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import pytest

from _cli import listed, tether
from tether.config import load_scenario
from tether.experiments.executors import Trial, run_trial

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "custom_strategy.py"
YAML = ROOT / "examples" / "centroid_pull.yaml"


def _flat(text: str) -> str:
    return " ".join(text.split())


@pytest.fixture(autouse=True)
def _forget_example(monkeypatch):
    """Each test imports the example itself (its registration is per process)."""
    from tether import plugins
    from tether.registry import STRATEGIES

    monkeypatch.setattr(plugins, "_LOADED", {})
    monkeypatch.delitem(sys.modules, "custom_strategy", raising=False)
    monkeypatch.delitem(STRATEGIES._items, "centroid_pull", raising=False)


def test_example_runs_from_yaml_with_plugin(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the run works from any folder
    code, out, err = tether(capsys, "run", str(YAML), "--out", "r", "--no-figures")
    assert code == 2 and "unknown strategy 'centroid_pull'" in err and "--plugin" in err
    code, out, err = tether(capsys, "run", str(YAML), "--plugin", str(EXAMPLE), "--out", "r",
                            "--no-figures")  # fmt: skip
    assert code == 0, err
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert summary["strategy"] == "centroid_pull" and summary["gain"] == 0.3


def test_validate_and_list_take_plugins(capsys):
    code, out, err = tether(capsys, "validate", str(YAML), "-p", str(EXAMPLE))
    assert code == 0 and "ok (centroid_pull, 15 robots, sweep of 2 combinations" in _flat(out), err
    code, out, _ = tether(capsys, "list", "--plugin", str(EXAMPLE))
    assert code == 0
    assert listed(out)["strategies"][:2] == ["centroid_pull", "connectivity"]


def test_plugin_by_module_name_from_the_current_folder(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(ROOT / "examples")
    code, _, err = tether(capsys, "validate", "centroid_pull.yaml", "--plugin", "custom_strategy")
    assert code == 0, err


def _spawned(trial: Trial):
    """Run a trial in a fresh interpreter (spawn: nothing inherited from this process)."""
    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as pool:
        return pool.submit(run_trial, trial).result(timeout=600)


def test_sweep_trials_import_the_plugin_where_they_run(tmp_path):
    data = load_scenario(YAML).model_dump(mode="json")
    data.pop("sweep")
    data["sim"]["max_steps"] = 5
    trial = Trial(data, str(YAML), str(YAML.parent), 2, str(tmp_path / "with"), (str(EXAMPLE),))
    outcome = _spawned(trial)
    assert outcome.error is None and outcome.summary["strategy"] == "centroid_pull"
    bare = Trial(data, str(YAML), str(YAML.parent), 2, str(tmp_path / "without"))
    outcome = _spawned(bare)
    assert "unknown strategy 'centroid_pull'" in outcome.error


def test_sweep_passes_plugins_to_trials(capsys, tmp_path):
    code, out, err = tether(capsys, "sweep", str(YAML), "-p", str(EXAMPLE), "--out",
                            str(tmp_path / "s"), "--executor", "serial")  # fmt: skip
    assert code == 0, err
    assert "2 runs (0 already done)" in _flat(out)


@pytest.mark.parametrize(
    ("source", "name", "message"),
    [
        (None, "no_such_plugin_module", "no module named 'no_such_plugin_module'"),
        (None, "missing.py", "file not found"),
        ("import no_such_dependency_xyz\n", "needs.py", "ModuleNotFoundError: No module named"),
        ("x = (\n", "broken.py", "SyntaxError at line 1"),
        ("raise RuntimeError('bad setup')\n", "raises.py", "RuntimeError: bad setup"),
        ("raise SystemExit(3)\n", "exits.py", "SystemExit: 3"),
        ("X = 1\n", "json.py", "a module named 'json' is already imported"),
        ("X = 1\n", "my-plugin.py", "'my-plugin' is not a valid module name"),
        (None, "not a module", "not a module name or a .py file"),
    ],
)
def test_bad_plugins_are_one_line(capsys, tmp_path, monkeypatch, source, name, message):
    monkeypatch.chdir(tmp_path)
    if source is not None:
        (tmp_path / name).write_text(source)
    code, out, err = tether(capsys, "run", "silent_demo", "--plugin", name)
    assert code == 2 and out == ""
    assert err.startswith(f"error: --plugin {name}: ") and message in err
    assert len(err.strip().splitlines()) == 1, err


def test_a_plugin_clashing_with_a_builtin_is_refused(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "clash.py").write_text(
        "from tether.registry import STRATEGIES\n@STRATEGIES.register('silent')\nclass Mine: pass\n"
    )
    code, _, err = tether(capsys, "run", "silent_demo", "--plugin", "clash.py")
    assert code == 2 and "strategy 'silent' is already registered by tether.silent" in err
