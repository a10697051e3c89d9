"""Every scenario parameter, generated from the pydantic models, and what tests its effect.

:func:`scenario_parameters` walks :class:`tether.config.Scenario` and the ``Params`` model
of every built-in strategy. Each parameter must have an effect test (registered with
:func:`effect` in a ``test_parameter_effects*.py`` module) or a declared reason why setting
it cannot change a run (:data:`NO_EFFECT`); ``test_parameter_effects.py`` fails on a
parameter that has neither, so a new parameter needs its test. Keys: ``sim.dt_s`` for the
scenario, ``silent:trajectory.speed_mps`` for a strategy's parameters.
"""

from __future__ import annotations

import types
import typing
from collections.abc import Callable, Iterator
from typing import Any

from pydantic import BaseModel

from tether.config import Scenario
from tether.plugins import BUILTINS
from tether.registry import STRATEGIES

#: key -> the tests that show its effect (filled by :func:`effect` at import)
EFFECTS: dict[str, list[str]] = {}

#: a built-in scenario of each built-in strategy, the base its parameters are changed on
STRATEGY_SCENARIOS: dict[str, str] = {
    "silent": "silent_demo",
    "connectivity": "connectivity_empty",
    "multi_target": "multi_target_empty",
    "recurrent": "recurrent_demo",
    "utility": "recurrent_demo",
    "unconstrained": "mission_unconstrained",
    "silent_exploration": "mission_silent",
    "continuous_exploration": "mission_continuous",
}

#: parameters whose value cannot change what a run does, and why
NO_EFFECT: dict[str, str] = {
    "description": "free text about the scenario; nothing reads it but the scenario.yaml copy",
    "strategy.params": "a mapping validated by the strategy's own Params model, whose "
    "fields are listed one by one (keys 'STRATEGY:field')",
}


def _models_in(annotation: Any) -> list[type[BaseModel]]:
    """The pydantic models inside an annotation (``X | None``, ``Annotated[X, ...]``)."""
    origin = typing.get_origin(annotation)
    if origin in (typing.Union, types.UnionType):
        return [m for arg in typing.get_args(annotation) for m in _models_in(arg)]
    if origin is typing.Annotated:
        return _models_in(typing.get_args(annotation)[0])
    if isinstance(annotation, type) and issubclass(annotation, BaseModel):
        return [annotation]
    return []


def model_fields(model: type[BaseModel], prefix: str = "") -> Iterator[str]:
    """Dotted names of the leaf fields of ``model`` (nested models walked into)."""
    for name, info in model.model_fields.items():
        nested = _models_in(info.annotation)
        if nested:
            for sub in nested:
                yield from model_fields(sub, f"{prefix}{name}.")
        else:
            yield f"{prefix}{name}"


def builtin_strategies() -> list[str]:
    return sorted(BUILTINS[STRATEGIES])


def scenario_parameters() -> list[str]:
    """Every parameter of a scenario: its own fields, then each built-in strategy's."""
    keys = list(model_fields(Scenario))
    for name in builtin_strategies():
        keys += [f"{name}:{k}" for k in model_fields(STRATEGIES.get(name).Params)]
    return sorted(dict.fromkeys(keys))


def effect(*keys: str) -> Callable[[Callable[..., Any]], Callable[..., Any]]:
    """Register the decorated test as showing the effect of ``keys``."""

    def decorator(fn: Callable[..., Any]) -> Callable[..., Any]:
        for key in keys:
            EFFECTS.setdefault(key, []).append(f"{fn.__module__}::{fn.__name__}")
        return fn

    return decorator
