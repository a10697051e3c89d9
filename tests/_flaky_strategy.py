"""A strategy that fails on purpose (for the sweep tests): ``fail: true`` raises mid-run."""

from __future__ import annotations

import numpy as np
from pydantic import BaseModel, ConfigDict

from tether.errors import ScenarioError
from tether.registry import STRATEGIES
from tether.sim import StepContext, Strategy, TeamState


class FlakyParams(BaseModel):
    model_config = ConfigDict(extra="forbid")
    fail: bool = False
    fail_at_step: int = 2
    #: "internal" raises RuntimeError (a bug), "input" a ScenarioError (bad input found late)
    fail_with: str = "internal"


@STRATEGIES.register("flaky")
class Flaky(Strategy):
    """Robots stand still; with ``fail`` the strategy raises RuntimeError at a given step."""

    name = "flaky"
    Params = FlakyParams

    def __init__(self, params: FlakyParams) -> None:
        super().__init__()
        self.params = params

    @classmethod
    def from_scenario(cls, params, scenario, world, initial, rng) -> Flaky:
        return cls(params)

    def step(self, ctx: StepContext) -> TeamState:
        if self.params.fail and ctx.step >= self.params.fail_at_step:
            if self.params.fail_with == "input":
                raise ScenarioError(f"flaky.yaml: strategy.params.fail: refused at step {ctx.step}")
            raise RuntimeError(f"flaky strategy failed at step {ctx.step}")
        return TeamState(ctx.state.positions.copy(), np.zeros_like(ctx.state.positions))
