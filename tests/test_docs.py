"""The Python examples in README.md and docs/*.md run as written (docs that cannot rot)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[1]
SHARED = ROOT.parent / "shared"
_BLOCK = re.compile(r"```python\n(.*?)```", re.DOTALL)

PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
BLOCKS = [
    (page, k, code) for page in PAGES for k, code in enumerate(_BLOCK.findall(page.read_text()))
]


def test_readme_has_python_examples():
    assert any(page.name == "README.md" for page, _, _ in BLOCKS), "README lost its examples"


@pytest.mark.parametrize(
    ("page", "index", "code"),
    BLOCKS,
    ids=[f"{page.relative_to(ROOT)}[{k}]" for page, k, _ in BLOCKS],
)
def test_python_block_runs(page, index, code, tmp_path, monkeypatch):
    if "../shared/" in code and not SHARED.exists():
        pytest.skip("needs ../shared (test data beside the repository)")
    # run as from the repository root (paths like ../shared/maps), writing into tmp_path
    repo = tmp_path / "repo"
    repo.mkdir()
    if SHARED.exists():
        (tmp_path / "shared").symlink_to(SHARED)
    monkeypatch.chdir(repo)
    monkeypatch.setenv("MPLBACKEND", "Agg")
    exec(compile(code, f"{page.name}[python block {index}]", "exec"), {"__name__": "__doc__"})
