"""Fill the registries with everything tether ships: one call, one place.

Importing a module that defines a plug-in registers it (decorator
registries, as in IR-SIM); :func:`load_builtins` imports the built-in ones so
that ``STRATEGIES``, ``SCENES`` and ``LINK_MODELS`` are complete. The runner
calls it when it is imported; your own plug-ins register when you import
their module.
"""

from __future__ import annotations

import tether.continuous.multi_target
import tether.continuous.strategy
import tether.recurrent.strategy
import tether.sensing.links
import tether.silent.strategy
import tether.world.scenes  # noqa: F401  (the imports above and this one register)
from tether.registry import LINK_MODELS, SCENES, STRATEGIES, TARGET_GENERATORS

BUILTIN_MODULES = (
    tether.world.scenes,
    tether.sensing.links,
    tether.silent.strategy,
    tether.continuous.strategy,
    tether.continuous.multi_target,
    tether.recurrent.strategy,
)


def load_builtins() -> dict[str, list[str]]:
    """Names in each registry once the built-in plug-ins are registered."""
    return {
        "strategies": STRATEGIES.names(),
        "scenes": SCENES.names(),
        "link models": LINK_MODELS.names(),
        "target generators": TARGET_GENERATORS.names(),
    }
