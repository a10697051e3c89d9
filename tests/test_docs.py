"""The Python examples in README.md run as written (documentation that cannot rot)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).parents[1]
_BLOCK = re.compile(r"```python\n(.*?)```", re.DOTALL)


def _blocks(path: Path) -> list[str]:
    return _BLOCK.findall(path.read_text())


README_BLOCKS = _blocks(ROOT / "README.md")


def test_readme_has_python_examples():
    assert README_BLOCKS, "README.md lost its Python examples"


@pytest.mark.parametrize("index", range(len(README_BLOCKS)))
def test_readme_python_block_runs(index, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # examples write run folders relative to the cwd
    monkeypatch.setenv("MPLBACKEND", "Agg")
    code = compile(README_BLOCKS[index], f"README.md[python block {index}]", "exec")
    exec(code, {"__name__": "__readme__"})
