"""The parameters of a scene (``world.params``), from its signature and numpydoc docstring.

A scene is a function ``(rng, **params) -> World``; each keyword parameter is a key of
``world.params``, documented in the function's ``Parameters`` section. Two keys more
are understood for every scene (:data:`COMMON_SCENE_KEYS`).
"""

from __future__ import annotations

import inspect
import re
from collections.abc import Callable

from tether.reference.schema import KeyDoc, type_name, unit_of, value_text

#: keys of ``world.params`` that every scene takes, besides its own parameters
COMMON_SCENE_KEYS: tuple[KeyDoc, ...] = (
    KeyDoc(
        "world.params.seed",
        "int",
        "",
        "the run's seed",
        ">= 0",
        "fixes a procedural layout independently of the run's seed",
    ),
    KeyDoc(
        "world.params.stand_in_path",
        "str",
        "",
        "null",
        "",
        "a file used, with a warning, when the scene's `path` is not found",
    ),
)

_SECTION = re.compile(r"^Parameters\n-+\n(.*?)(?:\n\n\S[^\n]*\n-+\n|\Z)", re.S | re.M)


def numpydoc_parameters(doc: str | None) -> dict[str, str]:
    """``{name: description}`` of a numpydoc ``Parameters`` section (one line each)."""
    match = _SECTION.search(inspect.cleandoc(doc or ""))
    if match is None:
        return {}
    out: dict[str, str] = {}
    names: list[str] = []
    for line in match.group(1).splitlines():
        if not line.strip():
            continue
        if not line.startswith((" ", "\t")):  # a name line: ``name`` or ``a, b : type``
            names = [n.strip() for n in line.split(":", 1)[0].split(",")]
            for n in names:
                out[n] = ""
        else:
            for n in names:
                out[n] = f"{out[n]} {line.strip()}".strip()
    return out


def scene_keys(factory: Callable) -> list[KeyDoc]:
    """The ``world.params`` keys of a scene function (``rng`` is not a key)."""
    docs = numpydoc_parameters(factory.__doc__)
    rows = []
    for name, p in inspect.signature(factory, eval_str=True).parameters.items():
        if name == "rng" or p.kind not in (p.KEYWORD_ONLY, p.POSITIONAL_OR_KEYWORD):
            continue
        key = f"world.params.{name}"
        default = "required" if p.default is inspect.Parameter.empty else value_text(p.default)
        annotation = p.annotation if p.annotation is not inspect.Parameter.empty else "any"
        rows.append(
            KeyDoc(key, type_name(annotation), unit_of(key), default, "", docs.get(name, ""))
        )
    return rows
