"""Built-in plug-ins are provided by name and imported on first lookup (``tether.plugins``).

The registries list every built-in name at once (``tether list``, the errors for an
unknown name, ``in``), a run imports only the strategy it uses, and registering by
decorator works as before: a user's plug-in from their own module, and a clash with a
built-in name reported as a clash. The cases that depend on what is imported run in a
fresh interpreter, so modules other tests imported do not hide an eager import.
"""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import pytest

from tether.plugins import BUILTINS
from tether.registry import Registry

SRC = Path(__file__).resolve().parents[1] / "src" / "tether"


def _python(code: str, *args: str) -> str:
    out = subprocess.run(
        [sys.executable, "-c", code, *args], capture_output=True, text=True, timeout=300
    )
    assert out.returncode == 0, out.stderr[-2000:]
    return out.stdout


def _registrations() -> dict[str, dict[str, str]]:
    """``@REGISTRY.register("name")`` decorators in the sources: registry -> {name: module}."""
    found: dict[str, dict[str, str]] = {}
    for path in SRC.rglob("*.py"):
        module = ".".join(path.relative_to(SRC.parent).with_suffix("").parts)
        for node in ast.walk(ast.parse(path.read_text())):
            if not isinstance(node, ast.FunctionDef | ast.ClassDef):
                continue
            for dec in node.decorator_list:
                if (
                    isinstance(dec, ast.Call)
                    and isinstance(dec.func, ast.Attribute)
                    and dec.func.attr == "register"
                    and isinstance(dec.func.value, ast.Name)
                    and dec.args
                    and isinstance(dec.args[0], ast.Constant)
                ):
                    found.setdefault(dec.func.value.id, {})[dec.args[0].value] = module
    return found


def test_every_builtin_registration_is_provided_with_its_module() -> None:
    """A new built-in plug-in missing from ``BUILTINS`` would be invisible to a lookup."""
    by_kind = {r.kind: names for r, names in BUILTINS.items()}
    found = _registrations()
    expect = {
        "strategy": found["STRATEGIES"],
        "scene": found["SCENES"],
        "link model": found["LINK_MODELS"],
        "target generator": found["TARGET_GENERATORS"],
    }
    assert by_kind == expect


@pytest.mark.parametrize(
    ("registry", "name", "module"),
    [(r, n, m) for r, names in BUILTINS.items() for n, m in names.items()],
    ids=lambda x: x if isinstance(x, str) else x.kind,
)
def test_a_provided_name_gets_the_object_its_module_defines(
    registry: Registry, name: str, module: str
) -> None:
    obj = registry.get(name)
    assert obj.__module__ == module
    assert name in registry and name in registry.names()


def test_a_run_imports_only_the_strategy_it_uses(tmp_path: Path) -> None:
    code = """
import sys
from tether.config import load_scenario
from tether.registry import STRATEGIES
from tether.runner import run

imported = lambda: sorted(m for m in ("tether.silent", "tether.continuous",
                                      "tether.recurrent") if m in sys.modules)
print("after import:", imported())
print("names:", STRATEGIES.names(), "silent" in STRATEGIES)
sc = load_scenario("recurrent_demo")
sc.sim.max_steps = 3
run(sc, out_dir=sys.argv[1], figures=False)
print("after the run:", imported())
"""
    out = _python(code, str(tmp_path / "run"))
    assert "after import: []" in out
    names = "['connectivity', 'continuous_exploration', 'multi_target', 'recurrent', 'silent', "
    names += "'silent_exploration', 'unconstrained', 'utility']"
    assert f"names: {names} True" in out
    assert "after the run: ['tether.recurrent']" in out


def test_unknown_names_list_provided_ones_without_importing_them() -> None:
    reg: Registry[type] = Registry("gadget")
    reg.provide("spanner", "tether_no_such_module")
    assert "spanner" in reg and reg.names() == ["spanner"] and list(reg) == ["spanner"]
    with pytest.raises(KeyError, match="unknown gadget 'wrench'; expected one of: spanner"):
        reg.get("wrench")
    with pytest.raises(ModuleNotFoundError):  # only asking for it imports it
        reg.get("spanner")


def test_a_provided_module_is_imported_on_first_lookup(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    (tmp_path / "tether_test_gadgets.py").write_text(
        "from tests_gadget_registry import REG\n\n"
        "@REG.register('spanner')\n"
        "def spanner():\n    return 1\n"
    )
    (tmp_path / "tests_gadget_registry.py").write_text(
        "from tether.registry import Registry\nREG = Registry('gadget')\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    import tests_gadget_registry

    reg = tests_gadget_registry.REG
    reg.provide("spanner", "tether_test_gadgets")
    assert "spanner" in reg and "tether_test_gadgets" not in sys.modules
    assert reg.get("spanner")() == 1
    assert "tether_test_gadgets" in sys.modules
    monkeypatch.delitem(sys.modules, "tether_test_gadgets")
    monkeypatch.delitem(sys.modules, "tests_gadget_registry")


def test_a_module_that_registers_nothing_is_an_error(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    (tmp_path / "tether_test_empty.py").write_text("")
    monkeypatch.syspath_prepend(str(tmp_path))
    reg: Registry[type] = Registry("gadget")
    reg.provide("spanner", "tether_test_empty")
    with pytest.raises(LookupError, match="registered no gadget 'spanner'"):
        reg.get("spanner")
    monkeypatch.delitem(sys.modules, "tether_test_empty")


def test_user_plugins_register_and_clash_as_before() -> None:
    """A user's own strategy registers by decorator; taking a built-in name still fails
    with the built-in's name, though that module was not imported yet."""
    code = """
import sys
from tether.registry import STRATEGIES
import tether.runner

@STRATEGIES.register("mine")
class Mine:
    pass

print("mine:", STRATEGIES.get("mine") is Mine, "mine" in STRATEGIES.names())
print("silent imported before:", "tether.silent.strategy" in sys.modules)
try:
    @STRATEGIES.register("silent")
    class Silent:
        pass
except ValueError as exc:
    print("clash:", exc)
"""
    out = _python(code)
    assert "mine: True True" in out
    assert "silent imported before: False" in out
    assert (
        "clash: strategy 'silent' is already registered by "
        "tether.silent.strategy.SilentStrategy" in out
    )


def test_a_builtin_name_taken_before_the_builtins_are_provided_still_clashes() -> None:
    """Registering ``silent`` before ``tether.runner`` is imported fails at that import,
    as it did when the runner imported every built-in module."""
    code = """
from tether.registry import STRATEGIES

@STRATEGIES.register("silent")
class Silent:
    pass

try:
    import tether.runner
except ValueError as exc:
    print("clash:", exc)
"""
    out = _python(code)
    assert "clash: strategy 'silent' is already registered by __main__.Silent" in out
