"""An installed package's plug-ins are listed by `tether list` and run from YAML.

A tiny package is written to a temporary folder and installed with pip into a fresh
virtual environment that sees this one's packages (tether and its dependencies), with
no network: ``--no-index --no-build-isolation --no-deps`` and a build backend inside the
package (``backend-path``), so the test needs neither setuptools nor wheel. The package
declares four entry points: a strategy given as ``module:Class`` that its module does
not register (tether registers it), a scene its module registers with the decorator,
a strategy named ``silent`` that clashes with the built-in one (ignored, and said so),
and one whose module is missing (listed; a scenario using it gets one line).
"""

from __future__ import annotations

import json
import os
import site
import subprocess
import sys
import sysconfig
import textwrap
from pathlib import Path

import pytest

from _cli import listed

BACKEND = '''
"""A PEP 517 backend that zips the package as it is (no setuptools, no wheel)."""
import base64, hashlib, zipfile
from pathlib import Path

NAME, VERSION = "tether_plugin_demo", "0.1"
DIST = f"{NAME}-{VERSION}.dist-info"


def get_requires_for_build_wheel(config_settings=None):
    return []


def build_wheel(wheel_directory, config_settings=None, metadata_directory=None):
    here = Path(__file__).parent
    metadata = f"Metadata-Version: 2.1\\nName: {NAME}\\nVersion: {VERSION}\\n"
    wheel_info = "Wheel-Version: 1.0\\nGenerator: test\\nRoot-Is-Purelib: true\\n"
    wheel_info += "Tag: py3-none-any\\n"
    files = {f"{NAME}.py": (here / f"{NAME}.py").read_bytes(),
             f"{DIST}/METADATA": metadata.encode(),
             f"{DIST}/WHEEL": wheel_info.encode(),
             f"{DIST}/entry_points.txt": (here / "entry_points.txt").read_bytes()}
    record = []
    for name, data in files.items():
        digest = base64.urlsafe_b64encode(hashlib.sha256(data).digest()).rstrip(b"=").decode()
        record.append(f"{name},sha256={digest},{len(data)}")
    record.append(f"{DIST}/RECORD,,")
    files[f"{DIST}/RECORD"] = ("\\n".join(record) + "\\n").encode()
    wheel = f"{NAME}-{VERSION}-py3-none-any.whl"
    with zipfile.ZipFile(Path(wheel_directory) / wheel, "w") as zf:
        for name, data in files.items():
            zf.writestr(name, data)
    return wheel
'''

MODULE = '''
"""A strategy (registered by tether from the entry point) and a scene (registered here)."""
import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from tether.registry import SCENES
from tether.sim import Strategy, TeamState
from tether.world import World


class DriftParams(BaseModel):
    model_config = ConfigDict(extra="forbid")
    speed_mps: float = Field(default=0.5, gt=0)


class Drift(Strategy):
    """Every robot moves along +x at speed_mps (the team keeps its shape)."""

    name = "plugin_drift"
    Params = DriftParams

    def __init__(self, speed_mps):
        super().__init__()
        self.speed_mps = speed_mps

    @classmethod
    def from_scenario(cls, params, scenario, world, initial, rng):
        return cls(params.speed_mps)

    def step(self, ctx):
        velocity = np.zeros_like(ctx.state.positions)
        velocity[:, 0] = self.speed_mps
        return TeamState(ctx.state.positions + velocity * ctx.dt_s, velocity)

    def metrics(self):
        return {"drift_speed_mps": self.speed_mps}


@SCENES.register("plugin_corridor")
def corridor(rng=None, *, length_m: float = 100.0):
    """A free 2-D corridor 20 m wide."""
    return World(dim=2, bounds_m=[[-10.0, -10.0], [length_m, 10.0]], name="plugin_corridor")
'''

ENTRY_POINTS = """
[tether.strategies]
plugin_drift = tether_plugin_demo:Drift
silent = tether_plugin_demo:Drift
plugin_broken = tether_plugin_demo_missing:Broken

[tether.scenes]
plugin_corridor = tether_plugin_demo
"""

PYPROJECT = """
[build-system]
requires = []
build-backend = "backend"
backend-path = ["."]

[project]
name = "tether_plugin_demo"
version = "0.1"
"""

SCENARIO = """
name: drift
world: {scene: plugin_corridor, dim: 2, params: {length_m: 60.0}}
team:
  n_robots: 4
  init: {kind: positions, positions: [[0, 0], [3, 0], [0, 3], [3, 3]]}
sensing: {range_m: 6.0}
sim: {dt_s: 1.0, max_steps: 20}
strategy: {name: plugin_drift, params: {speed_mps: 1.5}}
"""


def _make_package(root: Path) -> Path:
    pkg = root / "pkg"
    pkg.mkdir()
    (pkg / "backend.py").write_text(textwrap.dedent(BACKEND))
    (pkg / "tether_plugin_demo.py").write_text(textwrap.dedent(MODULE))
    (pkg / "entry_points.txt").write_text(ENTRY_POINTS.lstrip())
    (pkg / "pyproject.toml").write_text(PYPROJECT.lstrip())
    return pkg


def _venv_seeing_this_one(root: Path) -> Path:
    """A venv (no pip of its own) whose .pth adds this environment's site-packages."""
    venv = root / "venv"
    subprocess.run([sys.executable, "-m", "venv", "--without-pip", str(venv)], check=True,
                   timeout=120)  # fmt: skip
    python = venv / ("Scripts/python.exe" if os.name == "nt" else "bin/python")
    purelib = subprocess.run(
        [str(python), "-c", "import sysconfig; print(sysconfig.get_path('purelib'))"],
        capture_output=True, text=True, check=True, timeout=60,
    ).stdout.strip()  # fmt: skip
    ours = {sysconfig.get_path("purelib"), *site.getsitepackages()}
    lines = [f"import site; site.addsitedir({p!r})" for p in sorted(ours) if Path(p).is_dir()]
    lines += [p for p in sys.path if p.endswith("src") and Path(p, "tether").is_dir()]
    Path(purelib, "this_environment.pth").write_text("\n".join(lines) + "\n")
    return python


def _tether(python: Path, cwd: Path, *args: str) -> subprocess.CompletedProcess[str]:
    code = "import sys; from tether.cli import main; sys.argv[0] = 'tether'; main()"
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "PYTHONHOME")}
    return subprocess.run([str(python), "-c", code, *args], cwd=cwd, capture_output=True,
                          text=True, timeout=600, env={**env, "MPLBACKEND": "Agg"})  # fmt: skip


@pytest.fixture(scope="module")
def plugin_venv(tmp_path_factory: pytest.TempPathFactory) -> Path:
    root = tmp_path_factory.mktemp("plugin_package")
    pkg = _make_package(root)
    python = _venv_seeing_this_one(root)
    done = subprocess.run(
        [str(python), "-m", "pip", "install", "--no-index", "--no-build-isolation", "--no-deps",
         "--disable-pip-version-check", "-q", str(pkg)],
        capture_output=True, text=True, timeout=300,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-3000:]
    return python


def test_installed_plugins_are_listed(plugin_venv, tmp_path):
    done = _tether(plugin_venv, tmp_path, "list")
    assert done.returncode == 0, done.stderr
    sections = listed(done.stdout)
    assert "plugin_drift" in sections["strategies"]
    assert "plugin_corridor" in sections["scenes"]
    ignored = [line for line in done.stdout.splitlines() if line.startswith("ignored plug-in")]
    assert len(ignored) == 1 and "'silent'" in ignored[0] and "tether_plugin_demo" in ignored[0]


def test_installed_plugin_runs_from_yaml_in_any_folder(plugin_venv, tmp_path):
    (tmp_path / "drift.yaml").write_text(SCENARIO)
    done = _tether(plugin_venv, tmp_path, "run", "drift.yaml", "--out", "out", "--no-figures")
    assert done.returncode == 0, done.stderr
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["strategy"] == "plugin_drift" and summary["drift_speed_mps"] == 1.5
    assert summary["steps"] == 20 and summary["connected_all_steps"] is True
    # the built-in `silent` is still tether's, not the package's clashing entry point
    done = _tether(plugin_venv, tmp_path, "validate", "silent_demo")
    assert done.returncode == 0 and "(silent, 12 robots" in done.stdout, done.stderr


def test_plugin_is_absent_without_the_package(tmp_path):
    """The oracle of the tests above: this environment itself has no such plug-in."""
    (tmp_path / "drift.yaml").write_text(SCENARIO)
    done = _tether(Path(sys.executable), tmp_path, "validate", "drift.yaml")
    assert done.returncode == 2
    assert "strategy.name: unknown strategy 'plugin_drift'" in done.stderr


def test_a_broken_installed_plugin_is_one_line_and_harms_nothing_else(plugin_venv, tmp_path):
    (tmp_path / "broken.yaml").write_text(SCENARIO.replace("plugin_drift", "plugin_broken"))
    done = _tether(plugin_venv, tmp_path, "validate", "broken.yaml")
    assert done.returncode == 2 and len(done.stderr.strip().splitlines()) == 1, done.stderr
    assert "strategy 'plugin_broken' (package tether_plugin_demo 0.1): its module " in done.stderr
    assert "tether_plugin_demo_missing failed to import (ModuleNotFoundError" in done.stderr
    done = _tether(plugin_venv, tmp_path, "validate", "silent_demo")
    assert done.returncode == 0, done.stderr
