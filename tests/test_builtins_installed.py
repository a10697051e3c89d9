"""Every built-in scenario runs by name after a plain install, from an empty folder.

tether is built into a wheel from a copy of the checkout and installed (without
dependencies: the test environment has them) into a folder of its own, which is then
the only tether on ``PYTHONPATH``: the installed ``tether`` command runs each built-in
by name in an empty temporary folder, as a user would after ``pip install .``.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tether.config import builtin_scenarios, load_scenario

ROOT = Path(__file__).resolve().parents[1]
#: a hung build or run fails the test instead of stalling the suite
TIMEOUT_S = 600


def _outside_package(name: str) -> bool:
    """Whether built-in ``name`` names a file outside the package (run on its stand-in)."""
    path = load_scenario(name).world.params.get("path")
    return bool(path) and ".." in Path(path).parts


CASES = builtin_scenarios()


@pytest.fixture(scope="module")
def installed(tmp_path_factory: pytest.TempPathFactory) -> dict[str, str]:
    """``PATH`` and ``PYTHONPATH`` for the installed ``tether`` (its own folder only)."""
    work = tmp_path_factory.mktemp("install")
    source = work / "source"
    source.mkdir()
    for name in ("pyproject.toml", "setup.py", "README.md", "LICENSE"):
        if (ROOT / name).exists():
            shutil.copy(ROOT / name, source / name)
    shutil.copytree(ROOT / "src", source / "src",
                    ignore=shutil.ignore_patterns("__pycache__", "*.egg-info"))  # fmt: skip
    git = ["git", "-c", "user.name=tether", "-c", "user.email=tether@example.org"]
    for args in (["init", "-q"], ["add", "-A"], ["commit", "-q", "-m", "source"]):
        subprocess.run([*git, *args], cwd=source, check=True, capture_output=True, timeout=60)
    commit = subprocess.run(["git", "rev-parse", "HEAD"], cwd=source, capture_output=True,
                            text=True, check=True).stdout.strip()  # fmt: skip
    pip = [sys.executable, "-m", "pip", "--disable-pip-version-check", "-q"]
    wheels, site = work / "wheels", work / "site"
    subprocess.run([*pip, "wheel", "--no-deps", "-w", str(wheels), str(source)],
                   check=True, timeout=TIMEOUT_S, capture_output=True)  # fmt: skip
    (wheel,) = wheels.glob("tether-*.whl")
    subprocess.run([*pip, "install", "--no-deps", "--no-index", "--target", str(site), str(wheel)],
                   check=True, timeout=TIMEOUT_S, capture_output=True)  # fmt: skip
    path = f"{site / 'bin'}{os.pathsep}{os.environ['PATH']}"
    env = dict(os.environ, PYTHONPATH=str(site), PATH=path)
    where = subprocess.run(
        [sys.executable, "-c", "import tether; print(tether.__file__)"],
        env=env, cwd=work, capture_output=True, text=True, check=True,
    )  # fmt: skip
    assert Path(where.stdout.strip()).is_relative_to(site), where.stdout
    env["TETHER_BUILT_FROM"] = commit  # for the provenance tests below, not read by tether
    env["TETHER_SITE"] = str(site)
    return env


@pytest.mark.parametrize("name", CASES)
def test_builtin_runs_by_name_from_an_empty_folder(name, installed, tmp_path) -> None:
    cwd = tmp_path / "empty"
    cwd.mkdir()
    done = subprocess.run(
        ["tether", "run", name, "--set", "sim.max_steps=3", "--no-figures", "--out", "r"],
        env=installed, cwd=cwd, capture_output=True, text=True, timeout=TIMEOUT_S,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert "results: r" in done.stdout
    assert (cwd / "r" / "summary.json").is_file()
    assert sorted(p.name for p in cwd.iterdir()) == ["r"]
    if _outside_package(name):
        # the map beside a checkout is not shipped: the run says so and records the
        # stand-in it ran on, a file of the installed package kept in the run folder
        summary = json.loads((cwd / "r" / "summary.json").read_text())
        (kept,) = [f for f in summary["scene_files"] if f["key"] == "world.params.path"]
        assert kept["stand_in"] and Path(kept["used"]).is_relative_to(installed["TETHER_SITE"])
        assert (cwd / "r" / kept["copy"]).is_file()
        assert "stand-in" in done.stderr


def test_installed_package_animates_and_views(installed, tmp_path) -> None:
    """The replay's page, scripts and three.js ship with the package (package data)."""
    done = subprocess.run(
        ["tether", "run", "silent_demo", "--set", "sim.max_steps=3", "--no-figures",
         "--out", "r", "--animate", "--view"],
        env=installed, cwd=tmp_path, capture_output=True, text=True, timeout=TIMEOUT_S,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    page = (tmp_path / "r" / "replay.html").read_text()
    assert "three" in page.lower() and (tmp_path / "r" / "animation.gif").stat().st_size > 0


def test_installed_runs_record_the_commit_they_were_built_from(installed, tmp_path) -> None:
    done = subprocess.run(
        ["tether", "run", "silent_demo", "--set", "sim.max_steps=2", "--no-figures", "--out", "r"],
        env=installed, cwd=tmp_path, capture_output=True, text=True, timeout=TIMEOUT_S,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert summary["provenance"]["git_hash"] == installed["TETHER_BUILT_FROM"]


def test_a_project_repository_around_the_install_is_not_its_source(installed, tmp_path) -> None:
    """tether installed in a virtual environment inside the user's own git repository."""
    project = tmp_path / "project"
    shutil.copytree(installed["TETHER_SITE"], project / "venv" / "site")
    (project / "notes.txt").write_text("the user's work")
    git = ["git", "-c", "user.name=u", "-c", "user.email=u@example.org"]
    for args in (["init", "-q"], ["add", "notes.txt"], ["commit", "-q", "-m", "mine"]):
        subprocess.run([*git, *args], cwd=project, check=True, capture_output=True, timeout=60)
    env = dict(installed, PYTHONPATH=str(project / "venv" / "site"))
    got = subprocess.run([sys.executable, "-c", "from tether.runfolder import git_hash; "
                          "print(git_hash())"], env=env, cwd=project, capture_output=True,
                         text=True, check=True, timeout=TIMEOUT_S)  # fmt: skip
    assert got.stdout.strip() == installed["TETHER_BUILT_FROM"]
