"""``benchmarks/diagnose_stall.py``: a multi_target run's team at one instant.

It re-runs the run folder's scenario up to ``--at-s``, so what it prints describes the
recorded run only if the replay is exact: the tool compares the replayed positions with
``robots.parquet`` and prints the largest deviation, which must be 0. Bad input (not a
run folder, another strategy's run, a time outside the run) is one line, exit code 2.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
TOOL = ROOT / "benchmarks" / "diagnose_stall.py"


def tool(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(TOOL), *map(str, args)], capture_output=True,
                          text=True, timeout=240, cwd=ROOT)  # fmt: skip


def tether(*args: str) -> None:
    code = "import sys; from tether.cli import main; sys.exit(main())"
    subprocess.run([sys.executable, "-c", code, *args], check=True, capture_output=True,
                   timeout=240)  # fmt: skip


@pytest.fixture(scope="module")
def town_run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("stall") / "town"
    tether("run", "multi_target_town", "--set", "sim.max_steps=80", "--no-figures", "--out",
           str(out))  # fmt: skip
    return out


def test_replays_the_run_exactly_and_describes_the_prime(town_run: Path) -> None:
    done = tool(town_run, "--at-s", "7.0")
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0] == "replayed 70 steps; largest deviation from robots.parquet 0 m"
    assert "prime" in lines[1] and "lambda2 (weighted)" in lines[1]
    links = [ln for ln in lines if " hops " in ln and " W " in ln]
    assert links, done.stdout  # every link of the team, with its weight and clearance


@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["{missing}", "--at-s", "1"], "not a run folder"),
        (["{run}", "--at-s", "1000"], "the run covers 0 to 8 s"),
        (["{run}", "--at-s", "-1"], "the run covers"),
    ],
)
def test_bad_input_is_one_line(town_run: Path, tmp_path: Path, args: list[str], says: str):
    args = [a.format(run=town_run, missing=tmp_path / "nothing") for a in args]
    done = tool(*args)
    assert done.returncode == 2
    assert says in done.stderr and "Traceback" not in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1


def test_another_strategys_run_is_refused(tmp_path: Path) -> None:
    out = tmp_path / "silent"
    tether("run", "silent_demo", "--set", "sim.max_steps=5", "--no-figures", "--out", str(out))
    done = tool(out, "--at-s", "0.1")
    assert done.returncode == 2 and "looks at multi_target runs" in done.stderr
