"""Scenario keys from the pydantic models: type, unit, default, range and description.

:func:`model_keys` walks a model and the models nested in it; units come from the key's
name (``range_m`` is in metres, ``dt_s`` in seconds: the project's naming rule), ranges
from the fields' constraints, descriptions from the fields (or, for models that carry
none, from :data:`tether.reference.descriptions.KEY_DESCRIPTIONS`).
"""

from __future__ import annotations

import json
import types
import typing
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Literal

import annotated_types as at
from pydantic import BaseModel
from pydantic.fields import FieldInfo
from pydantic_core import PydanticUndefined

from tether.reference.descriptions import KEY_DESCRIPTIONS

#: name suffix -> unit, longest suffixes first (``_ns_per_m`` before ``_m``)
UNIT_SUFFIXES: tuple[tuple[str, str], ...] = (
    ("_ns_per_m", "N s/m"),
    ("_n_per_m", "N/m"),
    ("_per_s", "1/s"),
    ("_mps2", "m/s²"),
    ("_mps", "m/s"),
    ("_m_s", "m/s"),
    ("_dbm", "dBm"),
    ("_db", "dB"),
    ("_deg", "deg"),
    ("_rad", "rad"),
    ("_kg", "kg"),
    ("_j", "J"),
    ("_m", "m"),
    ("_s", "s"),
    ("_n", "N"),
)


@dataclass(frozen=True)
class KeyDoc:
    """One documented key: a scenario key, or a scene's parameter."""

    key: str
    type: str
    unit: str
    default: str
    range: str
    description: str


def unit_of(name: str) -> str:
    """The unit a key's name states (``""``: none stated, e.g. a count or a ratio)."""
    leaf = name.rsplit(".", 1)[-1].removesuffix("[]")
    for suffix, unit in UNIT_SUFFIXES:
        if leaf.endswith(suffix):
            return unit
    return ""


def _plain(annotation: Any) -> Any:
    """``Annotated[T, ...]`` as ``T``."""
    while typing.get_origin(annotation) is typing.Annotated:
        annotation = typing.get_args(annotation)[0]
    return annotation


def type_name(annotation: Any) -> str:
    """A reader's name of a type: ``float or null``, ``list of int``, ``one of: a, b``."""
    annotation = _plain(annotation)
    origin, args = typing.get_origin(annotation), typing.get_args(annotation)
    if origin is Literal:
        return "one of: " + ", ".join(str(a) for a in args)
    if origin in (typing.Union, types.UnionType):
        named = [type_name(a) for a in args if a is not type(None)]
        return " or ".join(named) + (" or null" if type(None) in args else "")
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return "mapping"
    if origin in (list, tuple, Sequence) or annotation in (list, tuple):
        inner = {type_name(a) for a in args if a is not Ellipsis}
        return "list" + (f" of {' or '.join(sorted(inner))}" if inner else "")
    if origin in (dict, Mapping) or annotation is dict:
        return "mapping" + (f" {type_name(args[0])} -> {type_name(args[1])}" if args else "")
    if annotation is Any:
        return "any"
    return getattr(annotation, "__name__", str(annotation))


def _number(value: Any) -> str:
    return f"{value:g}" if isinstance(value, float) else str(value)


def range_of(field: FieldInfo) -> str:
    """The field's numeric and length constraints: ``> 0, <= 1e+07``."""
    parts = []
    for m in field.metadata:
        for attr, sign in (("gt", ">"), ("ge", ">="), ("lt", "<"), ("le", "<=")):
            if isinstance(m, getattr(at, attr.capitalize())):
                parts.append(f"{sign} {_number(getattr(m, attr))}")
        if isinstance(m, at.MinLen):
            parts.append(f"length >= {m.min_length}")
        if isinstance(m, at.MaxLen):
            parts.append(f"length <= {m.max_length}")
    return ", ".join(parts)


def value_text(value: Any) -> str:
    """A default as YAML writes it: ``null``, ``true``, ``[4.0, 7.0]``, ``paper_random``."""
    if isinstance(value, BaseModel):
        return ""
    if value is None or isinstance(value, bool | list | tuple | dict):
        return json.dumps(value if not isinstance(value, tuple) else list(value))
    return _number(value)


def default_of(field: FieldInfo) -> str:
    """The default as text; ``required`` for a key without one."""
    if field.default_factory is not None:
        return value_text(field.default_factory())  # type: ignore[call-arg]
    if field.default is PydanticUndefined:
        return "required"
    return value_text(field.default)


def _nested(annotation: Any) -> tuple[type[BaseModel] | None, bool]:
    """The model a field holds (directly, optionally or as list items) and if in a list."""
    annotation = _plain(annotation)
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation, False
    origin, args = typing.get_origin(annotation), typing.get_args(annotation)
    if origin in (typing.Union, types.UnionType):
        for a in args:
            model, listed = _nested(a)
            if model is not None:
                return model, listed
    if origin in (list, tuple) and args:
        model, _ = _nested(args[0])
        if model is not None:
            return model, True
    return None, False


def first_line(doc: str | None) -> str:
    """The first sentence-line of a docstring (``""`` if none)."""
    return (doc or "").strip().split("\n", 1)[0].strip()


def description_of(model: type[BaseModel], name: str, field: FieldInfo) -> str:
    """The field's own description, else the documented table's, else the nested model's."""
    if field.description:
        return field.description
    for cls in model.__mro__:  # a field inherited from a documented parent model
        text = KEY_DESCRIPTIONS.get(f"{cls.__module__}.{cls.__qualname__}.{name}")
        if text:
            return text
    nested, _ = _nested(field.annotation)
    return first_line(nested.__doc__) if nested is not None else ""


def model_keys(model: type[BaseModel], prefix: str = "") -> list[KeyDoc]:
    """Every key of ``model`` and of the models nested in it, in declaration order."""
    rows: list[KeyDoc] = []
    for name, field in model.model_fields.items():
        key = f"{prefix}.{name}" if prefix else name
        nested, listed = _nested(field.annotation)
        rows.append(
            KeyDoc(
                key=key,
                type=type_name(field.annotation),
                unit=unit_of(key),
                default=default_of(field),
                range=range_of(field),
                description=description_of(model, name, field),
            )
        )
        if nested is not None:
            rows.extend(model_keys(nested, f"{key}[]" if listed else key))
    return rows
