"""Code named in a scenario: only functions of modules the user has loaded, never an import.

A scenario is data that people share, so a value such as
``strategy.params.trajectory.function: "my_paths:leader"`` never makes tether import
anything. It names a callable of a module that is *already loaded* in the process: the
user imported it before calling the Python API, loaded it with the command line's
plug-in option, or installed it as a plug-in. Modules of Python's standard library, of
tether and of the libraries tether runs on are not user code and are refused too (a
scenario must not be able to call ``sys:exit`` or ``code:interact``).

Fields that name code carry ``json_schema_extra={"code": True}`` in their pydantic
model; :func:`code_references` lists them, so ``tether validate`` can say which code a
scenario would call.
"""

from __future__ import annotations

import re
import sys
from collections.abc import Callable
from functools import lru_cache
from typing import Any

from pydantic import BaseModel

#: the marker of a pydantic field whose value names code (``module:callable``)
CODE_FIELD = {"code": True}

_SPEC = re.compile(r"^[A-Za-z_][\w]*(\.[A-Za-z_][\w]*)*:[A-Za-z_][\w]*$")


class UserCodeError(ValueError):
    """A code reference that is malformed or names a function tether may not call."""


def how_to_load(module: str) -> str:
    """The ways to load a module of one's own, in one clause (for error messages)."""
    return (
        f"load it first: `import {module}` before calling tether's Python API, "
        f"`tether run --plugin {module}` on the command line, or install it as a tether plug-in"
    )


@lru_cache(maxsize=1)
def _library_modules() -> frozenset[str]:
    """Top-level module names of the distributions tether needs (its requirements, closed).

    Read from the installed metadata; without it (a source tree on ``sys.path``) only
    the direct dependencies' usual module names are known.
    """
    from importlib import metadata

    fallback = {
        "numpy", "scipy", "networkx", "pydantic", "pydantic_core", "yaml", "typer", "click",
        "rich", "matplotlib", "pyarrow", "PIL", "highspy", "pyscipopt", "threadpoolctl",
        "numba", "llvmlite", "typing_extensions", "annotated_types", "shellingham",
        "pygments", "markdown_it", "mdurl", "dateutil", "six", "packaging", "pyparsing",
        "cycler", "kiwisolver", "fontTools", "contourpy", "mpl_toolkits", "pylab",
    }  # fmt: skip

    def norm(name: str) -> str:
        return re.sub(r"[-_.]+", "-", name).lower()

    try:
        dists = {norm(d.metadata["Name"]): d for d in metadata.distributions()}
        top_of: dict[str, set[str]] = {}
        for top, owners in metadata.packages_distributions().items():
            for owner in owners:
                top_of.setdefault(norm(owner), set()).add(top)
    except Exception:  # noqa: BLE001 - broken metadata: the known names only
        return frozenset(fallback)
    seen: set[str] = set()
    todo = ["tether"]
    while todo:
        name = todo.pop()
        if name in seen or name not in dists:
            continue
        seen.add(name)
        for req in dists[name].requires or []:
            if "extra ==" in req.replace('"', "").replace("'", ""):
                continue
            match = re.match(r"\s*([A-Za-z0-9][A-Za-z0-9._-]*)", req)
            if match:
                todo.append(norm(match.group(1)))
    modules = set(fallback)
    for name in seen:
        modules |= top_of.get(name, set())
    return frozenset(modules)


def is_library_module(name: str) -> bool:
    """``name`` belongs to Python, tether or a library tether runs on (not user code)."""
    top = name.split(".", 1)[0]
    if top == "__main__":
        return False
    return (
        top in sys.stdlib_module_names
        or top in sys.builtin_module_names
        or top == "tether"
        or top.startswith("_")
        or top in _library_modules()
    )


def resolve_callable(spec: Any) -> Callable[..., Any]:
    """The callable ``spec`` (``'module:name'``) names, from modules already loaded only.

    Raises
    ------
    UserCodeError
        One line: a malformed reference, a module that is not loaded (never imported
        here; the message says how to load it), a module of Python or of a library, a
        missing attribute, or one that is not callable.
    """
    if not isinstance(spec, str) or not _SPEC.match(spec):
        raise UserCodeError(
            f"expected 'module:function' naming a function of your own module, e.g. "
            f"'my_paths:leader' (got {str(spec)[:60]!r})"
        )
    module_name, _, attr = spec.partition(":")
    module = sys.modules.get(module_name)
    if module is None:
        raise UserCodeError(
            f"module {module_name!r} is not loaded, and tether never imports code named in a "
            f"scenario; {how_to_load(module_name)}"
        )
    if is_library_module(module_name):
        raise UserCodeError(
            f"{module_name!r} is part of Python, tether or a library tether uses, not your "
            "code; name a function of your own module"
        )
    fn = getattr(module, attr, None)
    if fn is None:
        raise UserCodeError(f"module {module_name!r} has no {attr!r}")
    if not callable(fn):
        raise UserCodeError(f"{spec} is not callable")
    return fn


def code_references(model: BaseModel, prefix: str = "") -> list[tuple[str, str]]:
    """``(field, 'module:function')`` for every set field of ``model`` that names code.

    Nested models are searched too; ``prefix`` is prepended to the dotted field names.
    """
    found: list[tuple[str, str]] = []
    for name, info in type(model).model_fields.items():
        value = getattr(model, name, None)
        field = f"{prefix}{name}"
        extra = info.json_schema_extra
        if isinstance(extra, dict) and extra.get("code") and isinstance(value, str):
            found.append((field, value))
        elif isinstance(value, BaseModel):
            found.extend(code_references(value, f"{field}."))
    return found
