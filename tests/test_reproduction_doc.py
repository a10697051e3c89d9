"""docs/explanation/reproduction.md stays usable: its links resolve, its commands name real files.

The page links to sections of other docs for numbers that change (recurrent.md), so a
renamed heading there must show up here, not as a dead link. The Fig. 9 section
(``<!-- fig9 -->`` ... ``<!-- /fig9 -->``) sets each of the paper's statements beside
ours and names the file its numbers come from.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
PAGE = DOCS / "explanation" / "reproduction.md"
_LINK = re.compile(r"\]\(([^)#\s]+\.md)(?:#([^)\s]+))?\)")


def slug(heading: str) -> str:
    """The anchor GitHub gives a Markdown heading."""
    text = heading.strip().lower()
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def anchors(page: Path) -> set[str]:
    headings = re.findall(r"^#{1,6} (.+)$", page.read_text(), flags=re.MULTILINE)
    return {slug(h) for h in headings}


def test_slug_matches_github():
    assert slug("Fig. 4: ILP against APX (theta = 12)") == "fig-4-ilp-against-apx-theta--12"
    assert (
        slug("The papers' campaigns (`scenarios/paper/`)") == "the-papers-campaigns-scenariospaper"
    )


@pytest.mark.parametrize("page", [PAGE, DOCS / "how-to" / "experiments.md"], ids=lambda p: p.name)
def test_links_resolve_to_files_and_headings(page):
    links = _LINK.findall(page.read_text())
    assert links, f"{page.name} has no links to other docs"
    for target, anchor in links:
        path = (page.parent / target).resolve()
        assert path.is_file(), f"{page.name}: {target} does not exist"
        if anchor:
            assert anchor in anchors(path), f"{page.name}: {target}#{anchor} is no heading"


def test_every_paper_file_named_exists_and_fig9_is_marked():
    text = PAGE.read_text()
    for name in set(re.findall(r"paper/([\w]+\.yaml)", text)):
        assert (ROOT / "src" / "tether" / "scenarios" / "paper" / name).is_file(), name
    for script in set(re.findall(r"python (benchmarks/[\w]+\.py)", text)):
        assert (ROOT / script).is_file(), script
    start, end = text.index("<!-- fig9 -->"), text.index("<!-- /fig9 -->")
    section = text[start:end]
    rows = [line for line in section.splitlines() if line.startswith("| ") and "---" not in line]
    assert len(rows) >= 1 + 4  # a header, then the paper's four statements (and more)
    assert "benchmarks/results/fig9.json" in section and "python benchmarks/fig9.py" in section
    assert "(docs/explanation/reproduction.md)" in (ROOT / "README.md").read_text()
