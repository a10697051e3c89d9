"""The import graph of ``src/tether``: no cycles, layers import only downward, small files.

Every ``import`` statement counts, at module level or inside a function (an
import inside a function hides a cycle from Python but not from a reader).
Layers are those of ``docs/explanation/architecture.md``.
"""

from __future__ import annotations

import ast
from pathlib import Path

import networkx as nx
import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
PACKAGE = SRC / "tether"

# (layer, module prefixes); the longest matching prefix decides a module's layer
LAYERS: list[tuple[str, tuple[str, ...]]] = [
    (
        "base",
        (
            "tether",
            "tether.errors",
            "tether.interrupts",
            "tether.progress",
            "tether.suggest",
            "tether.registry",
            "tether.geometry",
            "tether.floats",
            "tether.config",
        ),
    ),
    ("world", ("tether.world",)),
    ("graph", ("tether.graph",)),
    ("sensing", ("tether.sensing", "tether.comm")),
    ("motion", ("tether.paths", "tether.motion")),
    (
        "core",
        (
            "tether.sim",
            "tether.record",
            "tether.targets_recorded",
            "tether.team",
            "tether.viz",
            "tether.mission.log",
            "tether.mission.metrics",
        ),
    ),
    (
        "strategies",
        ("tether.silent", "tether.continuous", "tether.recurrent", "tether.mission"),
    ),
    (
        "running",
        ("tether.runner", "tether.plugins", "tether.scenario_world", "tether.kernel_cache"),
    ),
    (
        "experiments",
        ("tether.experiments", "tether.recurrent.report", "tether.mission.report"),
    ),
    (
        "interfaces",
        (
            "tether.cli",
            "tether.__main__",
            "tether.terminal",
            "tether.viewing",
            "tether.export",
            "tether.reference",
            "tether.envs",
        ),
    ),
]

#: (a, b): sub-packages of one strategy package where ``a`` never imports ``b`` (the
#: exploration of the continuous paper builds on its force, never the other way round;
#: the planners of the recurrent paper import nothing from its simulator)
NEVER_IMPORTS: list[tuple[str, str]] = [
    ("tether.continuous.connectivity", "tether.continuous.exploration"),
    ("tether.recurrent.planning", "tether.recurrent.exploration"),
]


def module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def modules() -> dict[str, Path]:
    return {module_name(p): p for p in PACKAGE.rglob("*.py")}


def imports_of(name: str, path: Path, known: set[str]) -> set[str]:
    """Every tether module ``name`` imports (resolved to modules, not symbols)."""
    tree = ast.parse(path.read_text(), str(path))
    is_pkg = path.name == "__init__.py"
    out: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            targets = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = name.split(".") if is_pkg else name.split(".")[:-1]
                anchor = anchor[: len(anchor) - (node.level - 1)]
                base = ".".join(anchor + ([base] if base else []))
            targets = [f"{base}.{a.name}" if f"{base}.{a.name}" in known else base
                       for a in node.names]  # fmt: skip
        else:
            continue
        for t in targets:
            while t and t not in known:  # a symbol or a missing module: its package
                t = t.rpartition(".")[0]
            if t and t != name:
                out.add(t)
    return out


def import_graph() -> nx.DiGraph:
    mods = modules()
    g = nx.DiGraph()
    g.add_nodes_from(mods)
    for name, path in mods.items():
        for target in imports_of(name, path, set(mods)):
            g.add_edge(name, target)
    return g


def layer_of(module: str) -> int:
    best, rank = -1, -1
    for k, (_, prefixes) in enumerate(LAYERS):
        for p in prefixes:
            if (module == p or module.startswith(p + ".")) and len(p) > best:
                best, rank = len(p), k
    return rank


def test_no_import_cycles_even_inside_functions() -> None:
    cycles = list(nx.simple_cycles(import_graph()))
    assert not cycles, "import cycles: " + "; ".join(" -> ".join(c + c[:1]) for c in cycles[:5])


def test_every_module_has_a_layer() -> None:
    assert [m for m in modules() if layer_of(m) < 0] == []


def test_layers_import_only_downward() -> None:
    g = import_graph()
    upward = [
        f"{a} ({LAYERS[layer_of(a)][0]}) imports {b} ({LAYERS[layer_of(b)][0]})"
        for a, b in g.edges
        if layer_of(b) > layer_of(a)
    ]
    assert upward == []


def _inside(module: str, package: str) -> bool:
    return module == package or module.startswith(package + ".")


@pytest.mark.parametrize(("lower", "upper"), NEVER_IMPORTS)
def test_a_sub_package_never_imports_the_one_built_on_it(lower: str, upper: str) -> None:
    g = import_graph()
    assert any(_inside(m, lower) for m in g) and any(_inside(m, upper) for m in g)
    wrong = sorted(
        f"{a} imports {b}" for a, b in g.edges if _inside(a, lower) and _inside(b, upper)
    )
    assert wrong == []


def test_no_source_file_over_500_lines() -> None:
    long = {str(p.relative_to(SRC)): n for p in PACKAGE.rglob("*.py")
            if (n := len(p.read_text().splitlines())) > 500}  # fmt: skip
    assert long == {}


@pytest.mark.parametrize(
    ("source", "expect"),
    [
        ("import tether.b\n", {"tether.b"}),
        ("def f():\n    from tether.b import thing\n", {"tether.b"}),
        ("from . import b\n", {"tether.b"}),
        ("from .b import thing\n", {"tether.b"}),
    ],
)
def test_the_walker_sees_function_level_and_relative_imports(
    tmp_path: Path, source: str, expect: set[str]
) -> None:
    """The checker itself: a cycle hidden inside a function must be found."""
    pkg = tmp_path / "tether"
    pkg.mkdir()
    (pkg / "__init__.py").write_text("")
    (pkg / "a.py").write_text(source)
    (pkg / "b.py").write_text("")
    known = {"tether", "tether.a", "tether.b"}
    global SRC
    old, SRC = SRC, tmp_path
    try:
        assert imports_of("tether.a", pkg / "a.py", known) == expect
    finally:
        SRC = old
