"""Did-you-mean: the closest of the known names to a misspelt one (``gama`` -> ``gamma``)."""

from __future__ import annotations

import difflib
from collections.abc import Iterable
from typing import Any, get_args

from pydantic import BaseModel

#: how alike (difflib's ratio) a known name must be to be suggested
CUTOFF = 0.6


def closest(word: str, choices: Iterable[str]) -> str | None:
    """The known name closest to ``word``, or ``None`` if none is close."""
    found = difflib.get_close_matches(str(word), [str(c) for c in choices], n=1, cutoff=CUTOFF)
    return found[0] if found else None


def did_you_mean(word: str, choices: Iterable[str]) -> str:
    """``" (did you mean 'gamma'?)"`` for a close name, else ``""``; to append to a message."""
    match = closest(word, choices)
    return f" (did you mean {match!r}?)" if match is not None and match != word else ""


def keys_at(model: Any, loc: tuple[Any, ...]) -> list[str]:
    """The keys the pydantic ``model`` accepts at ``loc`` (``[]`` where it cannot tell)."""
    for part in loc:
        if isinstance(part, int):  # an item of a list: the same model
            continue
        fields = getattr(model, "model_fields", None)
        if not isinstance(fields, dict) or part not in fields:
            return []
        model = model_in(fields[part].annotation)
    fields = getattr(model, "model_fields", None)
    return list(fields) if isinstance(fields, dict) else []


def model_in(annotation: Any) -> Any:
    """The pydantic model inside an annotation (``X``, ``X | None``, ``list[X]``, ...)."""
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return annotation
    models = [m for a in get_args(annotation) if (m := model_in(a)) is not None]
    return models[0] if len(models) == 1 else None
