"""``python -m tether.kernel_cache`` reaches every kernel module's warm-up.

Read from the source (nothing is compiled here): a ``warm_up()`` that no warm-up calls
leaves its kernels to be compiled in the middle of a run (or of a timed benchmark row),
and a warmed module that :data:`tether.jit.KERNEL_MODULES` leaves out does not change
the marker when its source changes.
"""

from __future__ import annotations

import ast
from pathlib import Path

from tether import jit

PACKAGE = Path(__file__).resolve().parents[1] / "src" / "tether"

#: modules with a ``warm_up()`` that the cache fills another way, and how
CALLED_OTHERWISE = {
    # small_fiedler_kernel is called with the strategy's settings by the connectivity warm-up
    "tether.graph.small_kernels",
}


def _module(path: Path) -> str:
    return ".".join(("tether", *path.relative_to(PACKAGE).with_suffix("").parts))


def _warm_up(path: Path) -> ast.FunctionDef | None:
    tree = ast.parse(path.read_text(), str(path))
    return next((n for n in tree.body if isinstance(n, ast.FunctionDef) and n.name == "warm_up"),
                None)  # fmt: skip


def modules_with_warm_up() -> dict[str, Path]:
    """Every module of tether with a top-level ``warm_up``."""
    return {_module(p): p for p in PACKAGE.rglob("*.py") if _warm_up(p) is not None}


def warm_ups_called(path: Path) -> set[str]:
    """The modules whose ``warm_up`` the ``warm_up`` of ``path`` imports."""
    fn = _warm_up(path)
    assert fn is not None, path
    return {node.module for node in ast.walk(fn)
            if isinstance(node, ast.ImportFrom) and node.module
            and any(a.name == "warm_up" for a in node.names)}  # fmt: skip


def reached() -> set[str]:
    """The warm-ups that ``tether.kernel_cache.warm_up`` runs, directly or through another."""
    known = modules_with_warm_up()
    seen: set[str] = set()
    todo = ["tether.kernel_cache"]
    while todo:
        name = todo.pop()
        for callee in warm_ups_called(known[name]):
            assert callee in known, f"{name} imports a warm_up that {callee} does not define"
            if callee not in seen:
                seen.add(callee)
                todo.append(callee)
    return seen


def test_every_kernel_warm_up_is_run_by_the_kernel_cache() -> None:
    missing = set(modules_with_warm_up()) - reached() - CALLED_OTHERWISE - {"tether.kernel_cache"}
    assert missing == set()


def test_the_marker_hashes_every_warmed_module() -> None:
    listed = {"tether." + rel.removesuffix(".py").replace("/", ".") for rel in jit.KERNEL_MODULES}
    assert reached() - listed == set()


def test_the_compile_command_is_the_kernel_cache() -> None:
    assert jit.COMPILE_COMMAND[1:] == ["-m", "tether.kernel_cache"]


def test_the_marker_hashes_every_compiled_module_the_switch_governs() -> None:
    """A kernel inlines what it calls from other modules (numba's cache keys on the
    caller's file only), so every module of cached kernels that ``TETHER_JIT`` switches
    must change the marker; the environments compile their own kernels apart."""
    compiled = {
        path.relative_to(PACKAGE).as_posix()
        for path in PACKAGE.rglob("*.py")
        if "@njit(cache=True" in path.read_text() and path.parent.name != "envs"
    }
    assert compiled - set(jit.KERNEL_MODULES) == set()
