"""Plant realistic bugs one at a time and see which test catches each (a mutation run).

Each bug of :mod:`planted_bugs_catalog` is planted in a private copy of the repository
(the checkout itself is never modified, so an interrupted run leaves nothing behind),
the test files it names run there (``pytest -x``, the numpy paths, the suite's
per-test timeout), and the copy is restored. A bug counts as

* **caught** when a test fails on an assertion (or ``pytest.fail``) and that test
  passes again once the bug is removed (checked);
* **crash** when the first failure is an exception raised in tether's code: the bug
  shows, but as an error a user would also see, not as a check of the right answer
  (an exception in the test's own code, such as a summary key it looks up that is
  gone, is the test noticing the bug: caught);
* **hang** when a test is stopped by the per-test timeout;
* **survived** when every named test passes.

Usage::

    python tools/planted_bugs.py                  # every bug; prints the table
    python tools/planted_bugs.py --only welch-as-student store-hash-ignores-sim
    python tools/planted_bugs.py --list           # the catalog, nothing run
    python tools/planted_bugs.py --write-docs     # also rewrite the table in the docs

``--write-docs`` replaces the generated part of ``docs/reference/test-suite.md`` and
writes the results as JSON to ``tools/results/planted_bugs.json``.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
from dataclasses import asdict, dataclass
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from planted_bugs_catalog import BUGS, Bug  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "reference" / "test-suite.md"
RESULTS = ROOT / "tools" / "results" / "planted_bugs.json"
BEGIN, END = "<!-- planted-bugs:begin -->", "<!-- planted-bugs:end -->"
#: what is never copied into the private repository
SKIP = {".git", "runs", "site", ".pytest_cache", ".ruff_cache", ".hypothesis", "__pycache__"}


@dataclass
class Outcome:
    id: str
    area: str
    what: str
    verdict: str  # caught, crash, hang, survived
    test: str  # the first failing test ("" if none)
    detail: str  # its first message line
    seconds: float


def check_catalog(bugs: list[Bug]) -> None:
    """Every bug's ``old`` occurs exactly once, and the planted file still compiles."""
    ids = [b.id for b in bugs]
    if len(set(ids)) != len(ids):
        raise SystemExit("planted_bugs: two bugs share an id")
    for bug in bugs:
        text = (ROOT / bug.path).read_text()
        count = text.count(bug.old)
        if count != 1:
            raise SystemExit(
                f"planted_bugs: {bug.id}: the text to replace occurs {count} times in "
                f"{bug.path} (the source changed: update the catalog)"
            )
        compile(text.replace(bug.old, bug.new), bug.path, "exec")
        for test in bug.tests:
            if not (ROOT / test.split("::")[0]).is_file():
                raise SystemExit(f"planted_bugs: {bug.id}: no test file {test}")


def private_copy() -> tuple[Path, Path]:
    """A copy of the repository (``shared/`` beside it, as in CI) and its numba cache."""
    base = Path(tempfile.mkdtemp(prefix="tether-planted-"))
    repo = base / "repo"
    shutil.copytree(ROOT, repo, ignore=lambda d, names: [
        n for n in names if n in SKIP or n.startswith(".venv")])  # fmt: skip
    shared = ROOT.parent / "shared"
    if shared.is_dir():
        (base / "shared").symlink_to(shared)
    (base / "numba-cache").mkdir()
    return repo, base / "numba-cache"


def run_pytest(repo: Path, cache: Path, tests: list[str], timeout_s: float) -> tuple[int, Path]:
    """``pytest -x`` on ``tests`` in ``repo``; its exit code and JUnit XML report."""
    report = repo.parent / "report.xml"
    report.unlink(missing_ok=True)
    env = {**os.environ, "PYTHONPATH": str(repo / "src"), "TETHER_JIT": "0",
           "NUMBA_CACHE_DIR": str(cache), "PYTHONDONTWRITEBYTECODE": "1"}  # fmt: skip
    env.pop("TETHER_REQUIRE_TOOLS", None)
    cmd = [sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider",
           "-o", f"timeout={timeout_s:g}", f"--junitxml={report}", *tests]  # fmt: skip
    proc = subprocess.Popen(cmd, cwd=repo, env=env, stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, start_new_session=True)  # fmt: skip
    try:
        code = proc.wait(timeout=timeout_s * 4 + 600)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        code = -1
    return code, report


#: the last line of a pytest traceback: ``path:line: ExceptionType``
_RAISED_AT = re.compile(r"^(\S+?):\d+: (\w[\w.]*)$")


@dataclass
class Failure:
    test: str  # the test id
    tag: str  # failure (the test's call) or error (its set-up or tear-down)
    message: str  # the first line of the message
    raised_in: str  # the file the exception was raised in ("" if unknown)


def first_failure(report: Path) -> Failure | None:
    """The first failing test of a JUnit XML report."""
    if not report.is_file():
        return None
    for case in ET.parse(report).getroot().iter("testcase"):
        for tag in ("failure", "error"):
            node = case.find(tag)
            if node is None:
                continue
            name = f"{case.get('classname', '').replace('.', '/')}.py::{case.get('name')}"
            message = (node.get("message") or node.text or "").strip().splitlines()
            raised = ""
            for line in reversed((node.text or "").strip().splitlines()):
                match = _RAISED_AT.match(line.strip())
                if match:
                    raised = match.group(1)
                    break
            return Failure(name, tag, message[0][:160] if message else "", raised)
    return None


def verdict_of(code: int, failure: Failure | None) -> tuple[str, str, str]:
    """``(verdict, test, detail)`` of one planted bug (see the module docstring).

    An exception raised in the tests' own code (a summary key the test looks up is gone)
    is the test noticing the bug; one raised in tether's code is a crash.
    """
    if code == 0:
        return "survived", "", ""
    if code == -1 or failure is None:
        return "hang" if code == -1 else "crash", "", f"pytest exit code {code}"
    line = failure.message
    if "Timeout" in line and line.startswith("Failed"):
        return "hang", failure.test, line
    assertion = line.startswith(("AssertionError", "assert", "Failed:"))
    in_test = failure.raised_in.startswith("tests/")
    caught = failure.tag == "failure" and (assertion or in_test)
    return ("caught" if caught else "crash"), failure.test, line


def plant(repo: Path, cache: Path, bug: Bug, timeout_s: float) -> Outcome:
    target = repo / bug.path
    original = target.read_text()
    start = time.monotonic()
    try:
        target.write_text(original.replace(bug.old, bug.new))
        code, report = run_pytest(repo, cache, list(bug.tests), timeout_s)
        verdict, test, detail = verdict_of(code, first_failure(report))
    finally:
        target.write_text(original)
    if verdict in ("caught", "crash") and test:  # the catching test passes without the bug
        code, _ = run_pytest(repo, cache, [test], timeout_s)
        if code != 0:
            verdict, detail = "invalid", f"{test} fails without the bug too"
    return Outcome(bug.id, bug.area, bug.what, verdict, test, detail,
                   round(time.monotonic() - start, 1))  # fmt: skip


def table(outcomes: list[Outcome]) -> str:
    """The Markdown table of a run, with its totals."""
    counts = {v: sum(o.verdict == v for o in outcomes) for v in
              ("caught", "crash", "hang", "survived", "invalid")}  # fmt: skip
    n = len(outcomes)
    lines = [
        f"{n} planted bugs: **{counts['caught']} caught by a failing test** "
        f"({100 * counts['caught'] / max(n, 1):.0f} %), {counts['crash']} only by a crash, "
        f"{counts['hang']} by a hang, {counts['survived']} survived"
        + (f", {counts['invalid']} invalid" if counts["invalid"] else "")
        + ".",
        "",
        "| bug | area | what it breaks | verdict | first failing test |",
        "| --- | --- | --- | --- | --- |",
    ]
    for o in outcomes:
        test = f"`{o.test.removeprefix('tests/')}`" if o.test else ""
        lines.append(f"| `{o.id}` | {o.area} | {o.what} | {o.verdict} | {test} |")
    return "\n".join(lines) + "\n"


def write_docs(text: str) -> None:
    page = DOC.read_text()
    head, rest = page.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    DOC.write_text(f"{head}{BEGIN}\n{text}{END}{tail}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--only", nargs="+", metavar="ID", help="plant only these bugs")
    ap.add_argument("--list", action="store_true", help="list the catalog and exit")
    ap.add_argument("--timeout", type=float, default=300.0, help="per-test timeout (s)")
    where = DOC.relative_to(ROOT)
    ap.add_argument("--write-docs", action="store_true",
                    help=f"rewrite the table in {where} and the JSON results")  # fmt: skip
    args = ap.parse_args(argv)
    bugs = [b for b in BUGS if not args.only or b.id in args.only]
    unknown = set(args.only or ()) - {b.id for b in BUGS}
    if unknown:
        raise SystemExit(f"planted_bugs: unknown bug ids: {', '.join(sorted(unknown))}")
    check_catalog(bugs)
    if args.list:
        for b in bugs:
            print(f"{b.id:38s} {b.area:20s} {b.path}")
        return 0
    repo, cache = private_copy()
    outcomes: list[Outcome] = []
    try:
        for k, bug in enumerate(bugs, 1):
            outcome = plant(repo, cache, bug, args.timeout)
            outcomes.append(outcome)
            print(f"[{k}/{len(bugs)}] {bug.id}: {outcome.verdict} {outcome.test} "
                  f"({outcome.seconds:.0f} s) {outcome.detail[:100]}", flush=True)  # fmt: skip
    finally:
        shutil.rmtree(repo.parent, ignore_errors=True)
    text = table(outcomes)
    print(text)
    if args.write_docs:
        write_docs(text)
        RESULTS.parent.mkdir(parents=True, exist_ok=True)
        RESULTS.write_text(json.dumps([asdict(o) for o in outcomes], indent=1) + "\n")
    return 0 if all(o.verdict == "caught" for o in outcomes) else 1


if __name__ == "__main__":
    sys.exit(main())
