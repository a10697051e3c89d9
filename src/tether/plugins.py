"""Fill the registries: the built-in plug-ins, installed packages' and the user's own.

Importing a module that defines a plug-in registers it (decorator registries, as in
IR-SIM). Plug-ins come from three places, all loaded here:

* **built-in**: this module *provides* every built-in name (:meth:`Registry.provide`)
  with the module that registers it: ``STRATEGIES``, ``SCENES``, ``LINK_MODELS`` and
  ``TARGET_GENERATORS`` list them all at once, and a module is imported the first
  time one of its names is looked up, so a run imports the strategy it uses and not
  the others (their packages and the libraries only they need);
* **installed packages** declare entry points in the groups of
  :data:`ENTRY_POINT_GROUPS` (``tether.strategies``, ``tether.scenes``,
  ``tether.link_models``, ``tether.target_generators``): the entry point's name is
  the plug-in's name, its value ``module:object``. They are provided the same way
  (listed at once, imported on first use); a module that does not register the name
  itself gets ``object`` registered under it. A name that is already built in is
  ignored and reported by ``tether list`` (:data:`IGNORED`);
* **the user's own module or file**, named by ``--plugin`` on the command line
  (:func:`load_plugin`): imported before the scenario is read, so its registrations
  (and the functions a scenario names) exist when the scenario is validated.
  Sweeps pass the loaded plug-ins (:func:`loaded_plugins`) to their trials, which
  load them again where they run (another process or machine).

The runner imports this module.
"""

from __future__ import annotations

import importlib
import importlib.metadata
import importlib.util
import sys
from pathlib import Path
from types import ModuleType

from tether.errors import TetherError
from tether.registry import LINK_MODELS, SCENES, STRATEGIES, TARGET_GENERATORS, Registry

#: registry -> {name: the module that defines and registers it}
BUILTINS: dict[Registry, dict[str, str]] = {
    STRATEGIES: {
        "silent": "tether.silent.strategy",
        "connectivity": "tether.continuous.connectivity.strategy",
        "multi_target": "tether.continuous.exploration.strategy",
        "recurrent": "tether.recurrent.strategy",
        "utility": "tether.recurrent.strategy",
        "unconstrained": "tether.mission.unconstrained",
        "silent_exploration": "tether.mission.silent_exploration",
        "continuous_exploration": "tether.mission.continuous_exploration",
    },
    SCENES: {
        "free": "tether.world.scenes",
        "empty": "tether.world.scenes",
        "map": "tether.world.scenes",
        "user_points": "tether.world.scenes",
        "town": "tether.world.procedural",
        "office": "tether.world.procedural",
    },
    LINK_MODELS: {
        "los": "tether.sensing.links",
        "disk": "tether.sensing.links",
        "signal": "tether.sensing.links",
    },
    TARGET_GENERATORS: {
        "fixed": "tether.continuous.exploration.targets",
        "schedule": "tether.continuous.exploration.targets",
        "paper_random": "tether.continuous.exploration.targets",
    },
}

#: every module that registers built-in plug-ins
BUILTIN_MODULES: tuple[str, ...] = tuple(
    dict.fromkeys(m for names in BUILTINS.values() for m in names.values())
)


#: registry -> the entry-point group through which installed packages provide plug-ins
ENTRY_POINT_GROUPS: dict[Registry, str] = {
    STRATEGIES: "tether.strategies",
    SCENES: "tether.scenes",
    LINK_MODELS: "tether.link_models",
    TARGET_GENERATORS: "tether.target_generators",
}

#: installed plug-ins not provided, one line each (a name that is built in, a bad value)
IGNORED: list[str] = []

#: the ``--plugin`` arguments loaded in this process, normalised (module names, absolute files)
_LOADED: dict[str, ModuleType] = {}


def load_builtins() -> dict[str, list[str]]:
    """Names in each registry: built-in and installed plug-ins provided (none imported)."""
    for registry, names in BUILTINS.items():
        for name, module in names.items():
            registry.provide(name, module)
    _provide_installed()
    return {
        "strategies": STRATEGIES.names(),
        "scenes": SCENES.names(),
        "link models": LINK_MODELS.names(),
        "target generators": TARGET_GENERATORS.names(),
    }


def _provide_installed() -> None:
    """Provide every installed package's entry points (once per process)."""
    if _provide_installed.done:  # type: ignore[attr-defined]
        return
    _provide_installed.done = True  # type: ignore[attr-defined]
    for registry, group in ENTRY_POINT_GROUPS.items():
        seen: set[str] = set()
        for ep in importlib.metadata.entry_points(group=group):
            if ep.name in seen:  # one distribution found twice on sys.path
                continue
            seen.add(ep.name)
            dist = getattr(ep, "dist", None)
            origin = f"package {dist.name} {dist.version}" if dist is not None else "a package"
            module, _, attr = ep.value.partition(":")
            module, attr = module.strip(), attr.strip() or None
            if ep.name in BUILTINS.get(registry, {}) or ep.name in registry:
                IGNORED.append(
                    f"{group} {ep.name!r} from {origin}: the name is taken (built in or "
                    "installed twice); the package must choose another name"
                )
            elif not module or not all(p.isidentifier() for p in module.split(".")):
                IGNORED.append(f"{group} {ep.name!r} from {origin}: value {ep.value!r} is not "
                               "module or module:object")  # fmt: skip
            else:
                registry.provide(ep.name, module, attr=attr, origin=origin)


_provide_installed.done = False  # type: ignore[attr-defined]


def loaded_plugins() -> tuple[str, ...]:
    """The ``--plugin`` modules and files loaded in this process (for a sweep's trials)."""
    return tuple(_LOADED)


def load_plugins(specs: list[str] | tuple[str, ...] | None) -> list[ModuleType]:
    """:func:`load_plugin` for each of ``specs`` (in order); ``None`` loads nothing."""
    return [load_plugin(spec) for spec in specs or ()]


def load_plugin(spec: str) -> ModuleType:
    """Import the user's plug-in: a module name (``my_pkg.strategies``) or a ``.py`` file.

    A file is imported as the module named by its stem (``examples/centroid.py`` is
    ``centroid``), with its folder on ``sys.path`` while it runs, so it can import the
    files beside it and a scenario can name its functions as ``centroid:path``. A
    module name is looked up on ``sys.path`` and then in the current folder. Loading
    the same plug-in again returns the module already imported.

    Raises
    ------
    TetherError
        ``--plugin SPEC: <problem and fix>``: no such file or module, a file whose
        name is another module's, or an exception while importing it (its type and
        message, never a traceback).
    """
    if not isinstance(spec, str) or not spec.strip():
        raise TetherError(f"--plugin {spec!r}: give a module name or a .py file")
    text = spec.strip()
    is_file = text.endswith(".py") or "/" in text or "\\" in text or Path(text).is_file()
    key = str(Path(text).expanduser().resolve()) if is_file else text
    if key in _LOADED:
        return _LOADED[key]
    module = _import_file(text, Path(key)) if is_file else _import_module(text)
    _LOADED[key] = module
    return module


def _import_module(name: str) -> ModuleType:
    if not all(part.isidentifier() for part in name.split(".")):
        raise TetherError(
            f"--plugin {name}: not a module name or a .py file; give e.g. my_strategies "
            "or path/to/my_strategies.py"
        )
    cwd = str(Path.cwd())
    added = cwd not in sys.path
    if added:
        sys.path.append(cwd)  # as `python -m`: modules in the current folder
    try:
        return _run_import(name, lambda: importlib.import_module(name))
    except ModuleNotFoundError as exc:
        if exc.name is not None and name.split(".")[0] != exc.name.split(".")[0]:
            raise _import_failed(name, exc) from None  # the plug-in imports a missing module
        raise TetherError(
            f"--plugin {name}: no module named {exc.name or name!r} on the Python path or in "
            "the current folder; install it, or give the path of its .py file"
        ) from None
    finally:
        if added and cwd in sys.path:
            sys.path.remove(cwd)


def _import_file(spec: str, path: Path) -> ModuleType:
    if not path.is_file():
        raise TetherError(f"--plugin {spec}: file not found; give the path of a .py file")
    if path.suffix != ".py":
        raise TetherError(f"--plugin {spec}: not a .py file; give a Python file or a module name")
    name = path.stem
    if not name.isidentifier():
        raise TetherError(
            f"--plugin {spec}: {name!r} is not a valid module name; rename the file "
            "(letters, digits and _)"
        )
    old = sys.modules.get(name)
    if old is not None:
        if Path(getattr(old, "__file__", "") or "").resolve() == path:
            return old
        raise TetherError(
            f"--plugin {spec}: a module named {name!r} is already imported "
            f"({getattr(old, '__file__', None) or 'built in'}); rename the file"
        )
    found = importlib.util.find_spec(name)
    if found is not None and Path(found.origin or "").resolve() != path:
        raise TetherError(
            f"--plugin {spec}: {name!r} is the name of an installed module ({found.origin}); "
            "rename the file"
        )
    module_spec = importlib.util.spec_from_file_location(name, path)
    if module_spec is None or module_spec.loader is None:  # pragma: no cover (a .py file)
        raise TetherError(f"--plugin {spec}: cannot be imported as a Python file")
    module = importlib.util.module_from_spec(module_spec)
    folder = str(path.parent)
    added = folder not in sys.path
    sys.modules[name] = module
    if added:
        sys.path.insert(0, folder)
    try:
        _run_import(spec, lambda: module_spec.loader.exec_module(module))  # type: ignore[union-attr]
    except ModuleNotFoundError as exc:  # the file imports a module that is not installed
        sys.modules.pop(name, None)
        raise _import_failed(spec, exc) from None
    except BaseException:
        sys.modules.pop(name, None)
        raise
    finally:
        if added and folder in sys.path:
            sys.path.remove(folder)
    return module


def _run_import(spec: str, do: object) -> ModuleType:
    """Run an import; anything it raises but a missing module becomes one line."""
    try:
        return do()  # type: ignore[operator]
    except ModuleNotFoundError:
        raise
    except (Exception, SystemExit) as exc:
        raise _import_failed(spec, exc) from None


def _import_failed(spec: str, exc: BaseException) -> TetherError:
    if isinstance(exc, TetherError):
        return TetherError(f"--plugin {spec}: {exc}")
    where = ""
    if isinstance(exc, SyntaxError) and exc.lineno:
        where = f" at line {exc.lineno}"
        exc = SyntaxError(exc.msg)
    problem = " ".join(f"{type(exc).__name__}{where}: {exc}".split())
    return TetherError(f"--plugin {spec}: importing it raised {problem[:300]}; fix the plug-in")


load_builtins()
