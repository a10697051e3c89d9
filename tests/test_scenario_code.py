"""A scenario never runs code the user did not choose.

``strategy.params.trajectory.function`` names a function; tether resolves it only in a
module the user has already loaded, never imports one, and refuses modules of Python and
of the libraries it runs on. ``tether validate`` says which code a scenario would call.
"""

from __future__ import annotations

import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
import yaml

from _cli import one_error_line, tether
from tether.config import load_scenario
from tether.errors import ScenarioError
from tether.runner import build, run
from tether.usercode import is_library_module, resolve_callable


def scenario_with_function(spec: str) -> dict:
    data = load_scenario("silent_demo").model_dump(mode="json")
    data["sim"]["max_steps"] = 3
    data["output"]["figures"] = False
    data["strategy"]["params"]["trajectory"] = {"kind": "function", "function": spec}
    return data


def write(tmp_path: Path, spec: str) -> Path:
    path = tmp_path / "shared.yaml"
    path.write_text(yaml.safe_dump(scenario_with_function(spec)))
    return path


@pytest.mark.parametrize("spec", ["sys:exit", "code:interact", "os:_exit", "builtins:input",
                                  "time:sleep", "subprocess:call", "tether.cli:main",
                                  "numpy:load", "yaml:load", "typer:prompt"])  # fmt: skip
def test_functions_of_python_and_its_libraries_are_refused(tmp_path, capsys, spec):
    path = write(tmp_path, spec)
    code, out, err = tether(capsys, "validate", str(path))
    line = one_error_line(code, err, "strategy.params.trajectory.function")
    assert "ok" not in out
    code, _, err = tether(capsys, "run", str(path), "--out", str(tmp_path / "out"))
    assert one_error_line(code, err) == line  # validate and run agree
    assert not (tmp_path / "out").exists()


def test_a_module_named_in_a_scenario_is_never_imported(tmp_path):
    """Imported, the module would write a file; the refusal says how to load it instead."""
    flag = tmp_path / "imported.flag"
    (tmp_path / "side_effect_mod.py").write_text(
        f"open({str(flag)!r}, 'w').write('ran')\ndef f(t):\n    return [t, 0.0]\n"
    )
    path = write(tmp_path, "side_effect_mod:f")
    for command in (["validate", str(path)], ["run", str(path), "--out", str(tmp_path / "o")]):
        proc = subprocess.run(
            [sys.executable, "-m", "tether.cli", *command],
            cwd=tmp_path,
            capture_output=True,
            text=True,
            timeout=120,
            env={"PYTHONPATH": str(tmp_path), "PATH": "/usr/bin:/bin", "TETHER_JIT": "0"},
        )
        one_error_line(proc.returncode, proc.stderr, "not loaded", "import side_effect_mod",
                       "--plugin side_effect_mod")  # fmt: skip
        assert not flag.exists()


def test_a_function_of_a_module_the_user_loaded_runs(tmp_path, monkeypatch):
    (tmp_path / "my_leader_paths.py").write_text(
        textwrap.dedent(
            """
            def leader(t):
                return [float(t), 0.0]
            """
        )
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.raises(ScenarioError, match="not loaded"):
        build(scenario_with_function("my_leader_paths:leader"))
    import my_leader_paths  # noqa: F401 - the user's choice: loading it

    outcome = run(scenario_with_function("my_leader_paths:leader"), out_dir=tmp_path / "run")
    assert outcome.summary["steps"] == 3


def test_validate_reports_the_code_a_scenario_would_call(tmp_path, capsys, monkeypatch):
    (tmp_path / "my_other_paths.py").write_text("def leader(t):\n    return [t, 0.0]\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    import my_other_paths  # noqa: F401

    code, out, err = tether(capsys, "validate", str(write(tmp_path, "my_other_paths:leader")))
    assert code == 0, err
    assert "calls my_other_paths:leader (strategy.params.trajectory.function)" in out
    code, out, _ = tether(capsys, "validate", "silent_demo")
    assert code == 0 and "calls" not in out


@pytest.mark.parametrize("spec", ["", "nocolon", "a:b:c", "../x:y", "mod:", ":f", 3, "a b:c"])
def test_malformed_references_are_refused(spec):
    with pytest.raises(ValueError, match="module:function"):
        resolve_callable(spec)


def test_library_modules_are_known():
    for name in ("os", "sys", "numpy.linalg", "scipy", "tether.runner", "pydantic", "rich",
                 "_pytest", "click"):  # fmt: skip
        assert is_library_module(name), name
    assert not is_library_module("__main__")
    assert not is_library_module("my_leader_paths")
