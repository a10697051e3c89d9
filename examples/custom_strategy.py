"""Plug your own controller into tether: a strategy in one small class.

Run it:  python examples/custom_strategy.py
It registers a strategy "centroid_pull" (every robot drifts towards the centroid of
what it senses, a consensus/rendezvous controller), then runs it from a scenario dict
exactly as `tether run` would run a YAML file, and prints the summary.
"""

from __future__ import annotations

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from tether.config import Scenario, scenario_from_dict
from tether.registry import STRATEGIES
from tether.runner import run
from tether.sim import StepContext, Strategy, TeamState
from tether.world import World


class CentroidParams(BaseModel):
    model_config = ConfigDict(extra="forbid")
    gain: float = Field(default=0.2, gt=0, le=1)


@STRATEGIES.register("centroid_pull")
class CentroidPull(Strategy):
    """Each robot moves a fraction ``gain`` of the way to the centroid of its measurements."""

    name = "centroid_pull"
    Params = CentroidParams

    def __init__(self, gain: float) -> None:
        super().__init__()
        self.gain = gain

    @classmethod
    def from_scenario(
        cls,
        params: CentroidParams,
        scenario: Scenario,
        world: World,
        initial: TeamState,
        rng: np.random.Generator,
    ) -> CentroidPull:
        return cls(params.gain)

    def step(self, ctx: StepContext) -> TeamState:
        obs = ctx.obs
        sums = np.zeros_like(ctx.state.positions)
        np.add.at(sums, obs.observer(), obs.measured)  # what each robot senses, nothing else
        counts = np.maximum(obs.degree(), 1)[:, None]
        step = self.gain * sums / counts
        return TeamState(ctx.state.positions + step, step / ctx.dt_s)

    def metrics(self) -> dict[str, float]:
        return {"gain": self.gain}


SCENARIO = {
    "name": "rendezvous",
    "seed": 2,
    "world": {"scene": "free", "dim": 2},
    "team": {"n_robots": 15, "init": {"kind": "random_connected", "spacing_m": 9.0}},
    "sensing": {"range_m": 12.0, "radial_error_m": 0.2, "angular_error_deg": 5.0},
    "sim": {"dt_s": 1.0, "max_steps": 60},
    "strategy": {"name": "centroid_pull", "params": {"gain": 0.3}},
}


def main(out_dir: str = "runs/rendezvous") -> dict:
    outcome = run(scenario_from_dict(SCENARIO, "examples/custom_strategy.py"), out_dir=out_dir)
    print(
        f"connected all steps: {outcome.summary['connected_all_steps']}; results in {outcome.path}"
    )
    return outcome.summary


if __name__ == "__main__":
    main()
