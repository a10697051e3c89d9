"""Every scenario key, in sections: the scenario, each strategy, target generator and scene.

Built-in plug-ins only (:data:`tether.plugins.BUILTINS`), so the reference does not
depend on what else is installed.
"""

from __future__ import annotations

from dataclasses import dataclass

from pydantic import BaseModel

from tether.config import Scenario
from tether.plugins import BUILTINS
from tether.reference.scene_keys import COMMON_SCENE_KEYS, scene_keys
from tether.reference.schema import KeyDoc, first_line, model_keys
from tether.registry import SCENES, STRATEGIES, TARGET_GENERATORS


@dataclass(frozen=True)
class Section:
    """A table of keys under one heading."""

    title: str
    intro: str
    rows: list[KeyDoc]
    model: type[BaseModel] | None = None


def _builtin(registry) -> list[str]:
    return list(BUILTINS[registry])


def scenario_sections() -> list[Section]:
    """The scenario's own keys, then each built-in strategy's, target generator's, scene's."""
    out = [Section("The scenario", first_line(Scenario.__doc__), model_keys(Scenario), Scenario)]
    for name in _builtin(STRATEGIES):
        cls = STRATEGIES.get(name)
        out.append(
            Section(
                f"Strategy `{name}`",
                first_line(cls.__doc__),
                model_keys(cls.Params, "strategy.params"),
                cls.Params,
            )
        )
    for name in _builtin(TARGET_GENERATORS):
        cls = TARGET_GENERATORS.get(name)
        out.append(
            Section(
                f"Target generator `{name}` (`multi_target`)",
                first_line(cls.__doc__),
                model_keys(cls.Params, "strategy.params.targets.params"),
                cls.Params,
            )
        )
    out.append(Section("Every scene", "Keys of `world.params` that every scene takes.",
                       list(COMMON_SCENE_KEYS)))  # fmt: skip
    for name in _builtin(SCENES):
        factory = SCENES.get(name)
        out.append(Section(f"Scene `{name}`", first_line(factory.__doc__), scene_keys(factory)))
    return out
