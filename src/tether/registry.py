"""Registries for pluggable behaviours (strategies, scenes, link models, ...).

As in IR-SIM, every plug-in point is a name -> factory table, so that a YAML
scenario can pick an implementation by name and users can add their own::

    from tether.registry import STRATEGIES

    @STRATEGIES.register("my_strategy")
    class MyStrategy: ...
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Generic, TypeVar

T = TypeVar("T")


def _qualname(obj: object) -> str:
    return f"{getattr(obj, '__module__', '?')}.{getattr(obj, '__qualname__', repr(obj))}"


class Registry(Generic[T]):
    """A named table of factories with a helpful error for unknown names."""

    def __init__(self, kind: str) -> None:
        self.kind = kind
        self._items: dict[str, T] = {}

    def register(self, name: str) -> Callable[[T], T]:
        def decorator(obj: T) -> T:
            old = self._items.get(name)
            if old is not None and old is not obj and _qualname(old) != _qualname(obj):
                raise ValueError(
                    f"{self.kind} {name!r} is already registered by {_qualname(old)}"
                )  # the same definition re-run (module reload, notebook) simply replaces it
            self._items[name] = obj
            return obj

        return decorator

    def get(self, name: str) -> T:
        try:
            return self._items[name]
        except KeyError:
            known = ", ".join(sorted(self._items)) or "none"
            raise KeyError(f"unknown {self.kind} {name!r}; expected one of: {known}") from None

    def names(self) -> list[str]:
        return sorted(self._items)

    def __contains__(self, name: object) -> bool:
        return name in self._items

    def __iter__(self) -> Iterator[str]:
        return iter(sorted(self._items))


STRATEGIES: Registry[type] = Registry("strategy")
SCENES: Registry[Callable] = Registry("scene")
LINK_MODELS: Registry[Callable] = Registry("link model")
TARGET_GENERATORS: Registry[type] = Registry("target generator")
