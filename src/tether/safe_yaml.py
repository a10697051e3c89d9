"""YAML read safely: PyYAML's safe loader, bounded in memory, with one-line errors.

A scenario file, a ``--set`` value and a ROS map YAML are all read here:
:func:`parse_yaml` refuses alias bombs and loops (:data:`MAX_YAML_VALUES`) and reports a
syntax error as one line naming the file, the line and the column.
"""

from __future__ import annotations

import re
from typing import Any

import yaml

from tether.errors import ScenarioError

#: YAML aliases may repeat values, but the expanded document holds at most this many
MAX_YAML_VALUES = 1_000_000


def _yaml_problem(exc: yaml.YAMLError) -> str:
    """A YAML parser error in one line: where and what."""
    mark = getattr(exc, "problem_mark", None)
    where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
    problem = getattr(exc, "problem", None) or getattr(exc, "reason", None) or "invalid YAML"
    return " ".join(f"not valid YAML{where}: {problem}".split())


def _check_expansion(data: Any, label: str) -> None:
    """Refuse YAML whose aliases expand beyond :data:`MAX_YAML_VALUES` values, or loop.

    PyYAML builds an alias as a reference to one object, so a "billion laughs"
    document loads in kilobytes and explodes only when copied or validated.
    Sizes are counted once per distinct object (linear in the document), and
    the top-level key holding the expansion is named.
    """
    sizes: dict[int, int] = {}
    active: set[int] = set()

    def size(obj: Any, field: str) -> int:
        if isinstance(obj, dict):
            children: Any = [*obj.keys(), *obj.values()]
        elif isinstance(obj, list):
            children = obj
        else:
            return 1
        key = id(obj)
        if key in sizes:
            return sizes[key]
        if key in active:
            raise ScenarioError(
                f"{label}: {field}: a YAML alias refers to a value that contains it (a loop); "
                "write the value out"
            )
        active.add(key)
        total = 1
        for child in children:
            total += size(child, field)
            if total > MAX_YAML_VALUES:
                raise ScenarioError(
                    f"{label}: {field}: YAML aliases expand to more than {MAX_YAML_VALUES:,} "
                    "values (an alias bomb?); write the values out or use fewer aliases"
                )
        active.discard(key)
        sizes[key] = total
        return total

    try:
        if isinstance(data, dict):
            for key, value in data.items():
                size(value, str(key))
        else:
            size(data, "(top level)")
    except RecursionError:
        raise ScenarioError(
            f"{label}: (top level): values are nested too deeply; flatten the document"
        ) from None


class YamlLoader(yaml.SafeLoader):
    """PyYAML's safe loader, with YAML 1.2's exponent floats (``1e-6``, ``2.5e3``): YAML
    1.1, which PyYAML follows, reads them as strings unless they have a dot and a sign."""


YamlLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)[eE][-+]?[0-9]+$"),
    list("-+0123456789."),
)


def parse_yaml(text: str | bytes, label: str) -> Any:
    """``yaml.safe_load`` bounded in time and memory, with one-line errors naming ``label``
    (exponent floats as in YAML 1.2: :class:`YamlLoader`)."""
    try:
        data = yaml.load(text, Loader=YamlLoader)  # noqa: S506 (a SafeLoader)
    except yaml.YAMLError as exc:
        raise ScenarioError(f"{label}: {_yaml_problem(exc)}") from None
    except RecursionError:
        raise ScenarioError(
            f"{label}: (top level): values are nested too deeply; flatten the document"
        ) from None
    _check_expansion(data, label)
    return data
