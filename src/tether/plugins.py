"""Fill the registries with everything tether ships: one table, one place.

Importing a module that defines a plug-in registers it (decorator registries, as in
IR-SIM). This module *provides* every built-in name (:meth:`Registry.provide`) with
the module that registers it: ``STRATEGIES``, ``SCENES``, ``LINK_MODELS`` and
``TARGET_GENERATORS`` list them all at once, and a module is imported the first time
one of its names is looked up, so a run imports the strategy it uses and not the
others (their packages and the libraries only they need). The runner imports this
module; your own plug-ins register when you import their module.
"""

from __future__ import annotations

from tether.registry import LINK_MODELS, SCENES, STRATEGIES, TARGET_GENERATORS, Registry

#: registry -> {name: the module that defines and registers it}
BUILTINS: dict[Registry, dict[str, str]] = {
    STRATEGIES: {
        "silent": "tether.silent.strategy",
        "connectivity": "tether.continuous.strategy",
        "multi_target": "tether.continuous.multi_target",
        "recurrent": "tether.recurrent.strategy",
        "utility": "tether.recurrent.strategy",
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
        "fixed": "tether.continuous.targets",
        "schedule": "tether.continuous.targets",
        "paper_random": "tether.continuous.targets",
    },
}

#: every module that registers built-in plug-ins
BUILTIN_MODULES: tuple[str, ...] = tuple(
    dict.fromkeys(m for names in BUILTINS.values() for m in names.values())
)


def load_builtins() -> dict[str, list[str]]:
    """Names in each registry, the built-in plug-ins provided (no module is imported)."""
    for registry, names in BUILTINS.items():
        for name, module in names.items():
            registry.provide(name, module)
    return {
        "strategies": STRATEGIES.names(),
        "scenes": SCENES.names(),
        "link models": LINK_MODELS.names(),
        "target generators": TARGET_GENERATORS.names(),
    }


load_builtins()
