"""Import every built-in strategy so that it registers itself in ``STRATEGIES``."""

from __future__ import annotations

import importlib

from tether.registry import STRATEGIES

BUILTIN_MODULES = (
    "tether.silent.strategy",
    "tether.continuous.strategy",
    "tether.recurrent.strategy",
)


def load_builtin_strategies() -> list[str]:
    """Register the built-in strategies; modules not present in this build are skipped."""
    for name in BUILTIN_MODULES:
        try:
            importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if exc.name != name:
                raise
    return STRATEGIES.names()
