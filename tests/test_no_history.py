"""The product describes itself as it is: no history of how it was made.

Docs, README, source (docstrings, comments, messages, scenario files), examples and the
benchmarks with their results name
no issue numbers, work sessions or numbered work periods, no branches, and tell no
"old tree against new tree" stories; neither do their file names. History belongs to
git log; a measurement of a rejected alternative stays only where it explains a current
design, worded as the alternative (an arc-flow formulation, a rule without the cap),
not as a moment in time.

The patterns are narrow on purpose: "branch" alone is a word of the domain (tree
branches, branch-and-cut), and so is "session" of a login shell; they are history only
with the names, ordinals and demonstratives below.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

_ORDINAL = (
    r"(?:first|second|third|fourth|fifth|sixth|seventh|eighth|ninth|tenth|eleventh|"
    r"twelfth|\d+(?:st|nd|rd|th))"
)
_BRANCHES = (
    r"(?:main|perf\d*|grass\d*|mt\d*|mtstep|eig|fuse|big|silent\d*|speed|ilp|recur|kernel|"
    r"dynamics|docs|harden|envs|params|plugins|commands|tests)"
)

#: what is history -> its pattern (case-insensitive)
HISTORY: dict[str, str] = {
    "an issue number": r"(?<![a-z])issues?[ _#-]*\d+",
    "a numbered work session or period": rf"\b{_ORDINAL}\s+(?:work\s+)?"
    r"(?:sessions?|periods?|sprints?)\b",
    "a session by its number": r"(?<![a-z])session[ _-]?\d+",
    "a session as a time": r"\b(?:this|that|same|previous|next|last|earlier|later)\s+sessions?\b"
    r"|\bsession's\b",
    "a work period": r"\bwork periods?\b",
    "a branch by name": rf"\bbranch(?:es)?\s+`?{_BRANCHES}`?(?![\w-])|`[\w-]+`\s+branch\b",
    "work on a branch": r"\b(?:on|in|from|of)\s+(?:this|that|the|our)\s+branch\b(?!-)",
    "old code against new code": r"\b(?:old|new)\s+(?:tree|code|checkout)s?\b|--old-(?:root|src)\b"
    r"|\bthe refactor\b|\bbefore this (?:change|fix|work)\b",
}
_PATTERNS = {what: re.compile(rx, re.IGNORECASE) for what, rx in HISTORY.items()}
_ANY = re.compile("|".join(f"(?:{rx})" for rx in HISTORY.values()), re.IGNORECASE)

#: the files searched: every page, the README, the package's source and data, the examples
SUFFIXES = {".md", ".py", ".yaml", ".yml", ".toml", ".js", ".html", ".css", ".txt", ".json"}
#: a tool that times the Fig. 9 trials under two checkouts of the user's choice: its
#: flags name them old and new (``--old-root``), which is what it does, not history
NOT_SEARCHED = {"benchmarks/bench_fig9_trials.py", "tests/test_no_history.py"}
#: names of files outside the searched ones that a page may still cite
CITED_AS_NAMED: tuple[str, ...] = ()


def searched_files() -> list[Path]:
    files = [ROOT / "README.md", ROOT / "mkdocs.yml"]
    for folder in ("docs", "src/tether", "examples", "benchmarks", "tests"):
        for path in sorted((ROOT / folder).rglob("*")):
            rel = path.relative_to(ROOT).as_posix()
            if (
                path.is_file()
                and path.suffix in SUFFIXES
                and "/vendor/" not in rel
                and rel not in NOT_SEARCHED
            ):
                files.append(path)
    return files


def history_in(text: str) -> list[tuple[str, str]]:
    """``(what, the matching text)`` for every piece of history in ``text``."""
    return [(what, m.group(0)) for what, rx in _PATTERNS.items() for m in rx.finditer(text)]


@pytest.mark.parametrize(
    ("text", "found"),
    [
        ("Measured in the seventh session on two cores.", True),
        ("the campaign of session 6 and fig9_session6_epyc.json", True),
        ("The performance goals of issue 14, old vs new", True),
        ("bench_issue14.py --old-root ../base", True),
        ("Branch `ilp` (node-separator model), made on the `recur` branch", True),
        ("what changed on this branch; the 3rd work period", True),
        ("the old code took 5-11 s and the new code 5 ms", True),
        ("robots of the branches it belongs to; branch-and-cut; the branch splits", False),
        ("a Dask worker per login session; a message layer's sessions", False),
        ("the two trees at a vertex; an issue of the map format", False),
    ],
)
def test_the_patterns_tell_history_from_the_domain(text, found):
    assert bool(history_in(text)) is found, history_in(text)


def test_no_history_in_the_product():
    files = searched_files()
    assert len(files) > 150
    problems = []
    for path in files:
        rel = path.relative_to(ROOT).as_posix()
        problems += [f"{rel} (file name): {what}: {hit!r}" for what, hit in history_in(rel)]
        text = path.read_text(errors="replace")
        for name in CITED_AS_NAMED:
            text = text.replace(name, "")
        if not _ANY.search(text):
            continue
        for number, line in enumerate(text.splitlines(), 1):
            problems += [f"{rel}:{number}: {what}: {hit!r}" for what, hit in history_in(line)]
    assert not problems, "history in the product (it belongs to git log):\n" + "\n".join(problems)
