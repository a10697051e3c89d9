"""The one YAML reader of tether: bounded in size, depth and alias expansion, strict on keys.

Every YAML file tether reads goes through :func:`read_yaml` or :func:`parse_yaml`:
scenarios and the papers' campaigns, ROS map_server map files, a sweep folder's
``sweep.yaml`` and ``--set`` values. Beyond PyYAML's safe loader (no Python objects),
it refuses, each with one line naming the file:

* a file over :data:`MAX_YAML_BYTES` (before it is parsed);
* nesting deeper than :data:`MAX_YAML_DEPTH` (while it is parsed);
* aliases that expand to more than :data:`MAX_YAML_VALUES` values ("billion laughs"),
  or that loop;
* a key given twice in one mapping (YAML forbids it; PyYAML would keep the last one);
* text that is not UTF-8.

Floats follow YAML 1.2 (``1e-6`` is a number, as in ROS's yaml-cpp), see :class:`YamlLoader`.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import yaml
from yaml.constructor import ConstructorError
from yaml.nodes import MappingNode, Node

from tether.errors import ScenarioError

__all__ = [
    "MAX_YAML_BYTES",
    "MAX_YAML_DEPTH",
    "MAX_YAML_VALUES",
    "YamlLoader",
    "parse_yaml",
    "read_yaml",
]

#: a YAML file larger than this is refused before it is parsed
MAX_YAML_BYTES = 16 * 2**20
#: mappings and lists nested deeper than this are refused while parsing
MAX_YAML_DEPTH = 64
#: YAML aliases may repeat values, but the expanded document holds at most this many
MAX_YAML_VALUES = 1_000_000

ErrorFactory = Callable[[str], Exception]


class _TooDeep(yaml.YAMLError):
    def __init__(self, mark: Any) -> None:
        super().__init__()
        self.problem_mark = mark
        self.problem = (
            f"values are nested too deeply (more than {MAX_YAML_DEPTH} levels); flatten the "
            "document"
        )


class _DuplicateKey(yaml.YAMLError):
    def __init__(self, key: Any, mark: Any) -> None:
        super().__init__()
        self.problem_mark = mark
        shown = repr(key) if len(repr(key)) <= 40 else repr(key)[:37] + "..."
        self.problem = f"key {shown} is given twice in one mapping; keep one"


class YamlLoader(yaml.SafeLoader):
    """PyYAML's safe loader with YAML 1.2's exponent floats (``1e-6``, ``2.5e3``: YAML
    1.1, which PyYAML follows, reads them as strings unless they have a dot and a sign),
    a depth limit and duplicate keys refused."""

    _depth = 0

    def compose_node(self, parent: Node | None, index: Any) -> Node | None:
        self._depth += 1
        try:
            if self._depth > MAX_YAML_DEPTH:
                raise _TooDeep(self.peek_event().start_mark)
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1

    def construct_mapping(self, node: Node, deep: bool = False) -> dict[Any, Any]:
        if isinstance(node, MappingNode):  # explicit keys only: a merge (<<) may be overridden
            seen: set[Any] = set()
            for key_node, _ in node.value:
                if key_node.tag == "tag:yaml.org,2002:merge":
                    continue
                key = self.construct_object(key_node, deep=True)
                try:
                    if key in seen:
                        raise _DuplicateKey(key, key_node.start_mark)
                    seen.add(key)
                except TypeError:  # an unhashable key: PyYAML reports it below
                    pass
        return super().construct_mapping(node, deep=deep)


#: the tags of plain data; any other (``!!set``, ``!!binary``, ``!!timestamp``, a Python
#: tag, a custom ``!tag``) is refused: tether reads numbers, text, lists and mappings
PLAIN_TAGS = frozenset(
    f"tag:yaml.org,2002:{t}" for t in ("str", "int", "float", "bool", "null", "seq", "map")
)


def _construct_plain(self: YamlLoader, node: Node, deep: bool = False) -> Any:
    if node.tag not in PLAIN_TAGS:
        tag = node.tag.replace("tag:yaml.org,2002:", "!!")
        problem = (
            f"tag {tag} is not plain data (tether reads numbers, text, lists and mappings); "
            "remove the tag"
        )
        raise ConstructorError(None, None, problem, node.start_mark)
    return yaml.SafeLoader.construct_object(self, node, deep=deep)


YamlLoader.construct_object = _construct_plain  # type: ignore[method-assign]
# dates stay text (YAML 1.2's core schema): no implicit timestamps
YamlLoader.yaml_implicit_resolvers = {
    first: [(tag, rx) for tag, rx in resolvers if tag != "tag:yaml.org,2002:timestamp"]
    for first, resolvers in yaml.SafeLoader.yaml_implicit_resolvers.items()
}
YamlLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"^[-+]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)[eE][-+]?[0-9]+$"),
    list("-+0123456789."),
)


def _problem(exc: yaml.YAMLError) -> str:
    """A YAML parser error in one line: where and what."""
    mark = getattr(exc, "problem_mark", None)
    where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
    problem = getattr(exc, "problem", None) or getattr(exc, "reason", None) or "invalid YAML"
    if isinstance(exc, ConstructorError) and "constructor for the tag" in str(problem):
        problem = f"{problem} (tether reads plain YAML: remove the tag)"
    return " ".join(f"not valid YAML{where}: {problem}".split())


def _check_expansion(data: Any, label: str, error: ErrorFactory) -> None:
    """Refuse YAML whose aliases expand beyond :data:`MAX_YAML_VALUES` values, nest deeper
    than :data:`MAX_YAML_DEPTH` levels, or loop.

    PyYAML builds an alias as a reference to one object, so a "billion laughs"
    document loads in kilobytes and explodes only when copied or validated (and a chain
    of aliases nests deeper than the text does). Sizes and heights are counted once per
    distinct object (linear in the document), and the top-level key holding them is named.
    """
    seen: dict[int, tuple[int, int]] = {}  # id -> (values, height)
    active: set[int] = set()

    def measure(obj: Any, field: str, depth: int) -> tuple[int, int]:
        if isinstance(obj, dict):
            children: Any = [*obj.keys(), *obj.values()]
        elif isinstance(obj, list):
            children = obj
        else:
            return 1, 0
        key = id(obj)
        if key not in seen:
            if key in active:
                raise error(
                    f"{label}: {field}: a YAML alias refers to a value that contains it (a "
                    "loop); write the value out"
                )
            if depth > MAX_YAML_DEPTH:
                raise error(
                    f"{label}: {field}: values are nested too deeply (more than "
                    f"{MAX_YAML_DEPTH} levels, through aliases); flatten the document"
                )
            active.add(key)
            total, height = 1, 0
            for child in children:
                n, h = measure(child, field, depth + 1)
                total, height = total + n, max(height, h + 1)
                if total > MAX_YAML_VALUES:
                    raise error(
                        f"{label}: {field}: YAML aliases expand to more than "
                        f"{MAX_YAML_VALUES:,} values (an alias bomb?); write the values out or "
                        "use fewer aliases"
                    )
            active.discard(key)
            seen[key] = (total, height)
        total, height = seen[key]
        if depth + height > MAX_YAML_DEPTH:
            raise error(
                f"{label}: {field}: values are nested too deeply (more than {MAX_YAML_DEPTH} "
                "levels, through aliases); flatten the document"
            )
        return total, height

    if isinstance(data, dict):
        for key, value in data.items():
            measure(value, str(key), 1)
    else:
        measure(data, "(top level)", 0)


def parse_yaml(text: str | bytes, label: str, error: ErrorFactory = ScenarioError) -> Any:
    """YAML text as Python data, bounded in time and memory (see the module docstring).

    Parameters
    ----------
    text
        The document (bytes are decoded as UTF-8).
    label
        The file (or option) named in error messages.
    error
        Makes the exception raised from a one-line message (default
        :class:`tether.errors.ScenarioError`).
    """
    if isinstance(text, bytes):
        text = _decode(text, label, error)
    if len(text.encode("utf-8", "surrogatepass")) > MAX_YAML_BYTES:
        raise error(f"{label}: more than {MAX_YAML_BYTES // 2**20} MiB of YAML; shorten it")
    try:
        data = yaml.load(text, Loader=YamlLoader)  # noqa: S506 (a SafeLoader)
    except yaml.YAMLError as exc:
        raise error(f"{label}: {_problem(exc)}") from None
    except RecursionError:
        raise error(f"{label}: (top level): values are nested too deeply; flatten it") from None
    _check_expansion(data, label, error)
    return data


def _decode(raw: bytes, label: str, error: ErrorFactory) -> str:
    try:
        return raw.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise error(
            f"{label}: not UTF-8 text (byte {raw[exc.start]:#04x} at offset {exc.start}); "
            "save it as UTF-8"
        ) from None


def read_yaml(
    path: Path, label: str, error: ErrorFactory = ScenarioError, what: str = "a YAML file"
) -> Any:
    """Read and parse a YAML file with :func:`parse_yaml`'s bounds, size checked first.

    ``OSError`` (missing, a folder, unreadable) is left to the caller, which knows what
    the file is for.
    """
    if path.exists() and not path.is_file() and not path.is_dir():
        raise error(f"{label}: not a regular file (a pipe or a device?); give a YAML file")
    size = path.stat().st_size if path.is_file() else 0
    if size > MAX_YAML_BYTES:
        raise error(
            f"{label}: file is {size / 2**20:.0f} MiB; {what} may be at most "
            f"{MAX_YAML_BYTES // 2**20} MiB"
        )
    with open(path, "rb") as fh:
        raw = fh.read(MAX_YAML_BYTES + 1)  # a file that grew since stat still stops here
    if len(raw) > MAX_YAML_BYTES:
        raise error(f"{label}: file is over {MAX_YAML_BYTES // 2**20} MiB; shorten it")
    return parse_yaml(_decode(raw, label, error), label, error)
