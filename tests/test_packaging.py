"""tether imports only what its install declares (the README's plain `pip install .`).

A module the install does not declare (``click`` came in through the test
extra's dask) works in the test environment and breaks a user's. Every import
in ``src/tether`` must be the standard library, tether itself, a declared
dependency, or an optional extra imported inside ``try: ... except ImportError`` -- in
the module itself or in its package's ``__init__.py`` (Python runs a package's
``__init__`` before any of its modules, so ``tether.envs`` guards ``tether.envs.*``).
"""

from __future__ import annotations

import ast
import importlib.metadata
import re
import sys
from pathlib import Path

import tomllib

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "tether"


def _normal(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def _declared() -> tuple[set[str], set[str]]:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]

    def names(reqs: list[str]) -> set[str]:
        out = {_normal(re.split(r"[<>=!~\[; ]", r, maxsplit=1)[0]) for r in reqs}
        for r in reqs:  # "dask[distributed]" brings the distribution "distributed" too
            extras = re.search(r"\[([^\]]*)\]", r)
            out |= {_normal(e) for e in extras.group(1).split(",")} if extras else set()
        return out

    optional = set().union(*(names(v) for v in project["optional-dependencies"].values()))
    return names(project["dependencies"]), optional


def _imports(path: Path) -> list[tuple[str, bool]]:
    """Top-level module names imported by ``path``, each with: inside try/except ImportError."""
    tree = ast.parse(path.read_text(), str(path))
    guarded: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Try) and any(
            isinstance(h.type, ast.Name) and h.type.id in ("ImportError", "ModuleNotFoundError")
            for h in node.handlers
        ):
            guarded.update(id(n) for stmt in node.body for n in ast.walk(stmt))
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(a.name.split(".")[0], id(node) in guarded) for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            found.append((node.module.split(".")[0], id(node) in guarded))
    return found


def _guarded_by_packages(path: Path) -> set[str]:
    """Modules that the ``__init__.py`` of ``path``'s packages import inside a guard."""
    out: set[str] = set()
    for folder in path.parents:
        if folder == SRC.parent:
            break
        init = folder / "__init__.py"
        if init != path and init.exists():
            out |= {module for module, guarded in _imports(init) if guarded}
    return out


def test_every_import_is_declared():
    required, optional = _declared()
    dists = importlib.metadata.packages_distributions()
    problems = []
    for path in sorted(SRC.rglob("*.py")):
        by_package = _guarded_by_packages(path)
        for module, guarded in _imports(path):
            guarded = guarded or module in by_package
            if module == "tether" or module in sys.stdlib_module_names or module == "__future__":
                continue
            owners = {_normal(d) for d in dists.get(module, [module])}
            if owners & required:
                continue
            if owners & optional and guarded:
                continue
            where = path.relative_to(ROOT)
            problems.append(f"{where}: import {module} ({', '.join(sorted(owners))})")
    assert problems == []


def test_click_is_never_imported_directly():
    """typer bundles its own click; `import click` fails after a plain install."""
    assert [p for p in SRC.rglob("*.py") if any(m == "click" for m, _ in _imports(p))] == []


def test_the_checker_sees_an_undeclared_import(tmp_path):
    module = tmp_path / "m.py"
    module.write_text("import click\ntry:\n    import distributed\nexcept ImportError:\n    pass\n")
    assert _imports(module) == [("click", False), ("distributed", True)]
