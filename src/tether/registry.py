"""Registries for pluggable behaviours (strategies, scenes, link models, ...).

As in IR-SIM, every plug-in point is a name -> factory table, so that a YAML
scenario can pick an implementation by name and users can add their own::

    from tether.registry import STRATEGIES

    @STRATEGIES.register("my_strategy")
    class MyStrategy: ...

A name can also be *provided* before its module is imported
(``STRATEGIES.provide("my_strategy", "my_package.strategy")``): it is listed, found by
``in`` and named in the error for an unknown name at once, and its module is imported
the first time :meth:`Registry.get` asks for it (the built-in plug-ins are provided
this way by :mod:`tether.plugins`, so a run imports only the strategy it uses).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable, Iterator
from typing import Generic, TypeVar

from tether.errors import TetherError

T = TypeVar("T")


def _qualname(obj: object) -> str:
    return f"{getattr(obj, '__module__', '?')}.{getattr(obj, '__qualname__', repr(obj))}"


class Registry(Generic[T]):
    """A named table of factories with a helpful error for unknown names.

    Parameters
    ----------
    kind
        What the factories make, for messages (``"strategy"``, ``"scene"``, ...).
    """

    def __init__(self, kind: str) -> None:
        self.kind = kind
        self._items: dict[str, T] = {}
        self._providers: dict[str, str] = {}  # name -> module whose import registers it
        self._objects: dict[str, str] = {}  # name -> attribute of the module to register
        self._origins: dict[str, str] = {}  # name -> where a plug-in came from (installed)
        self._loading: set[str] = set()  # names whose module is being imported

    def register(self, name: str) -> Callable[[T], T]:
        """A decorator that registers its object under ``name``.

        A name provided by another module (:meth:`provide`) is loaded first, so a
        clash with it is reported as if that module had been imported before.
        """

        def decorator(obj: T) -> T:
            provider = self._providers.get(name)
            module = str(getattr(obj, "__module__", None))
            own = module == provider or module.startswith(f"{provider}.")
            if provider is not None and not own and name not in self._loading:
                self._load(name)
            old = self._items.get(name)
            if old is not None and old is not obj and _qualname(old) != _qualname(obj):
                raise ValueError(
                    f"{self.kind} {name!r} is already registered by {_qualname(old)}"
                )  # the same definition re-run (module reload, notebook) simply replaces it
            self._items[name] = obj
            self._providers.pop(name, None)
            self._objects.pop(name, None)
            return obj

        return decorator

    def provide(
        self, name: str, module: str, *, attr: str | None = None, origin: str | None = None
    ) -> None:
        """Declare that importing ``module`` registers ``name`` (imported on first use).

        Parameters
        ----------
        name
            The registered name.
        module
            The dotted name of the module that defines and registers it (its objects'
            ``__module__``). If another module registered ``name`` already, this one is
            imported now, so the clash is reported as it would be without laziness.
        attr
            The module's attribute to register under ``name`` when importing the
            module does not register it (an installed plug-in's entry point
            ``module:attr``).
        origin
            Where the plug-in comes from (``package tether-foo 1.0``), for messages: a
            plug-in with an origin that fails to import is reported as a
            :class:`~tether.errors.TetherError` naming it, not as an internal error.
        """
        old = self._items.get(name)
        if old is None:
            self._providers[name] = module
            if attr is not None:
                self._objects[name] = attr
            if origin is not None:
                self._origins[name] = origin
        elif getattr(old, "__module__", None) != module:
            importlib.import_module(module)  # its registration reports the clash

    def origin(self, name: str) -> str | None:
        """Where the installed plug-in ``name`` comes from (``None`` for the others)."""
        return self._origins.get(name)

    def _load(self, name: str) -> None:
        """Import the module that provides ``name`` (and register its attribute if asked)."""
        module = self._providers[name]
        origin = self._origins.get(name)
        self._loading.add(name)
        try:
            loaded = importlib.import_module(module)
        except Exception as exc:
            if origin is None:
                raise
            problem = " ".join(f"{type(exc).__name__}: {exc}".split())
            raise TetherError(
                f"{self.kind} {name!r} ({origin}): its module {module} failed to import "
                f"({problem[:200]}); reinstall or uninstall that package"
            ) from None
        finally:
            self._loading.discard(name)
        attr = self._objects.get(name)
        if name not in self._items and attr is not None:
            obj: object = loaded
            for part in attr.split("."):
                obj = getattr(obj, part, None)
            if obj is not None:
                self._loading.add(name)
                try:
                    self.register(name)(obj)  # type: ignore[arg-type]
                finally:
                    self._loading.discard(name)
        if name not in self._items:
            where = f" ({origin})" if origin else ""
            message = f"{module}{where} was imported but registered no {self.kind} {name!r}"
            if origin is None:
                raise LookupError(message)
            raise TetherError(f"{message}; reinstall or uninstall that package")

    def get(self, name: str) -> T:
        """The factory registered under ``name`` (its module imported if provided)."""
        if name not in self._items and name in self._providers:
            self._load(name)
        try:
            return self._items[name]
        except KeyError:
            known = ", ".join(self.names()) or "none"
            raise KeyError(f"unknown {self.kind} {name!r}; expected one of: {known}") from None

    def names(self) -> list[str]:
        """Every registered or provided name, sorted (no module is imported)."""
        return sorted(self._items.keys() | self._providers.keys())

    def __contains__(self, name: object) -> bool:
        return name in self._items or name in self._providers

    def __iter__(self) -> Iterator[str]:
        return iter(self.names())


STRATEGIES: Registry[type] = Registry("strategy")
SCENES: Registry[Callable] = Registry("scene")
LINK_MODELS: Registry[Callable] = Registry("link model")
TARGET_GENERATORS: Registry[type] = Registry("target generator")
