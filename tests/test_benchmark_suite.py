"""The benchmark suite (``python benchmarks/run.py``): its registry runs, its tables hold.

No timing is asserted: the suite's numbers depend on the machine. What a user relies
on: ``--quick`` runs a row end to end and writes a results file only where ``--out``
says; every row states a goal or a peer; a bad row name is a one-line error; and every
table the docs show between ``<!-- suite:... -->`` markers is exactly what the named
results file gives (so each number there comes from the suite's command).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
RUN = ROOT / "benchmarks" / "run.py"
sys.path.insert(0, str(ROOT / "benchmarks"))

import suite.rows  # noqa: E402, F401  (registers the rows)
from suite import report  # noqa: E402
from suite.core import ROWS, Line  # noqa: E402


def run(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(RUN), *args], capture_output=True, text=True,
                          timeout=240, cwd=ROOT)  # fmt: skip


def test_quick_runs_a_row_and_writes_only_to_out(tmp_path: Path) -> None:
    out = tmp_path / "results.json"
    before = sorted(p.name for p in (ROOT / "benchmarks" / "results").iterdir())
    done = run("--quick", "--only", "placement", "--out", str(out))
    assert done.returncode == 0, done.stderr
    doc = json.loads(out.read_text())
    rec = doc["rows"]["placement"]
    assert rec["quick"] is True and rec["lines"]
    line = rec["lines"][0]
    assert line["goal"] == "<= 30 s" and line["ours"] > 0 and line["met"] in (True, False)
    assert doc["machine"]["cpu_count"] >= 1
    assert sorted(p.name for p in (ROOT / "benchmarks" / "results").iterdir()) == before


def test_unknown_row_is_one_line() -> None:
    done = run("--quick", "--only", "no_such_row")
    assert done.returncode == 2
    assert "unknown row(s) no_such_row" in done.stderr and "Traceback" not in done.stderr


def test_every_row_is_listed_with_its_title() -> None:
    done = run("--list")
    assert done.returncode == 0
    assert [ln.split()[0] for ln in done.stdout.splitlines()] == list(ROWS)


@pytest.mark.parametrize(
    ("line", "met"),
    [
        (Line("t", "us", 40.0, goal="<= 50 us", goal_value=50.0), True),
        (Line("t", "us", 60.0, goal="<= 50 us", goal_value=50.0), False),
        (Line("t", "/s", 12.0, goal=">= 10 /s", goal_value=10.0, higher_is_better=True), True),
        (Line("t", "us", 9.0, goal_value=1.0, goal_on="ratio", peer="p", peer_value=10.0), True),
        (Line("t", "us", 11.0, goal_value=1.0, goal_on="ratio", peer="p", peer_value=10.0), False),
        (Line("t", "s", 1.0), None),
    ],
)
def test_a_goal_is_met_as_stated(line: Line, met: bool | None) -> None:
    assert line.met is met


def test_every_marked_table_is_what_its_results_file_gives() -> None:
    seen = 0
    for page in report.PAGES:
        text = (ROOT / page).read_text()
        for table, file, body in report.marked_tables(text):
            doc = json.loads((ROOT / file).read_text())
            assert body.rstrip("\n") == report.TABLES[table](doc), f"{page}: table {table}"
            assert not any(rec["quick"] for rec in doc["rows"].values()), file
            seen += 1
    assert seen >= 5


def test_the_summary_table_names_every_row_of_its_file() -> None:
    text = (ROOT / "docs" / "performance.md").read_text()
    (file,) = {f for t, f, _ in report.marked_tables(text) if t == "summary"}
    doc = json.loads((ROOT / file).read_text())
    assert set(doc["rows"]) == set(ROWS), "a full run records every row"
