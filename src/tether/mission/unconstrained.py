"""The ``unconstrained`` paradigm: independent frontier explorers with no connectivity rule.

Each robot greedily heads for the frontier of best utility on its own map (eq. (1)
of the recurrent-connectivity paper, ``g(f) / d^2``), exactly as the Utility
baseline of :mod:`tether.recurrent.baseline_utility` does but with its return rule
switched off (``ratio = 0``): nothing ever calls a robot back to the base station
while it has a frontier. Robots that meet share maps (the mission's data layer), and a
robot with no frontier left on its map heads back towards the base station to deliver
what it holds. It is the speed bound the connected paradigms pay against.
"""

from __future__ import annotations

from typing import Literal

from pydantic import Field

from tether.recurrent.baseline_utility import UtilityStrategy
from tether.recurrent.strategy import ExplorationParams, ExplorationPlugin
from tether.registry import STRATEGIES

__all__ = ["UnconstrainedExploration", "UnconstrainedParams"]


class UnconstrainedParams(ExplorationParams):
    """Frontier exploration with no connectivity rule."""

    coordination: Literal["greedy", "none"] = Field(
        default="greedy",
        description="greedy: robots that can talk do not pick one frontier twice; none: "
        "every robot on its own",
    )


@STRATEGIES.register("unconstrained")
class UnconstrainedExploration(ExplorationPlugin):
    """Independent frontier explorers: no recurrent or continuous connectivity."""

    name = "unconstrained"
    Params = UnconstrainedParams

    @classmethod
    def make_policy(cls, params: UnconstrainedParams) -> UtilityStrategy:
        return UtilityStrategy(ratio=0.0, coordination=params.coordination, name=cls.name)
