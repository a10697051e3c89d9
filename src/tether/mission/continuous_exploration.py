"""The ``continuous_exploration`` paradigm: continuous connectivity on the mission.

Nestmeyer et al.'s decentralized multi-target exploration (``multi_target``: roles, the
prime-traveler election, Algorithm 2's traveling force on the connectivity force of
App. A) explores the mission's map, with its targets generated online from the
frontiers of the team's shared map (the paper's framing: targets come from an
exploration layer) and the base station a fixed node of the weighted graph, so every
robot is linked to it at every step while the controller keeps lambda2 above
``lambda2_min`` (measured by the guard, not vetoed: ``controller_success``).

The team starts around the base station in the controller's safe set: the base
station is drawn as for every paradigm (or given by ``base_m``); if it is within
``R'o`` of an obstacle it moves to the nearest point of the same free region that is
not (the controller's start needs it); the robots are then placed around it, each
within ``R's`` of another node (:func:`tether.continuous.connectivity.placement.safe_team`).

The mission's data layer, sensor and links are the ones of every paradigm
(:mod:`tether.mission.continuous_policy`). ``speed_m_s`` is the robots' top speed.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any, Literal

import numpy as np
from pydantic import Field, ValidationError
from scipy import ndimage

from tether.config import format_validation_error
from tether.continuous.connectivity.placement import safe_team
from tether.continuous.exploration.params import MultiTargetParams
from tether.errors import ScenarioError
from tether.mission.continuous_policy import ContinuousPolicy
from tether.recurrent.strategy import ExplorationParams, ExplorationPlugin
from tether.registry import STRATEGIES
from tether.sim import TeamState
from tether.world.grid import OccupancyGrid
from tether.world.world import World

__all__ = ["ContinuousExploration", "ContinuousExplorationParams"]


class ContinuousExplorationParams(ExplorationParams):
    """The controller's Table 2 preset, its period and the targets' stay and timeout."""

    preset: Literal["outdoor", "office", "experiment"] = Field(
        default="office", description="column of the continuous paper's Table 2"
    )
    cruise_fraction: float = Field(
        default=0.75, gt=0, lt=1, description="v_cruise as a share of the top speed speed_m_s"
    )
    control_period_s: float = Field(
        default=0.1, gt=0, le=10, description="the controller's period (a step runs several)"
    )
    stay_s: float = Field(default=3.0, ge=0, le=1e6, description="Delta t at every target")
    target_timeout_s: float | None = Field(
        default=None, gt=0, le=1e9,
        description="a target not reached this long after it was taken is dropped (null: "
        "never; a prime that makes no progress for stall_timeout_s drops it anyway)",
    )  # fmt: skip
    multi_target: dict[str, Any] = Field(
        default_factory=dict, description="any other multi_target parameter (overrides)"
    )


def controller_params(params: ContinuousExplorationParams, source: str) -> MultiTargetParams:
    """The ``multi_target`` parameters: the preset, the top speed, the overrides."""
    data: dict[str, Any] = {
        "preset": params.preset,
        "max_speed_mps": params.speed_m_s,
        "v_cruise_mps": params.cruise_fraction * params.speed_m_s,
        "guard": "detect",
        **params.multi_target,
    }
    try:
        return MultiTargetParams.model_validate(data)
    except ValidationError as exc:
        raise ScenarioError(
            format_validation_error(source, exc, prefix="strategy.params.multi_target")
        ) from None


def clear_base(grid: OccupancyGrid, base_m: np.ndarray, clearance_m: float) -> np.ndarray | None:
    """The point nearest ``base_m`` of its free region with more than ``clearance_m``
    to every obstacle cell (a cell centre; ``None`` if the region has none)."""
    cell = grid.to_cell(np.asarray(base_m, dtype=float)[None])[0]
    labels, _ = ndimage.label(~grid.occupied, structure=np.ones((3, 3), bool))
    region = labels == labels[tuple(cell)]
    ok = region & (grid.distance_field_m > clearance_m)
    if ok[tuple(cell)]:
        return np.asarray(base_m, dtype=float)
    cand = np.argwhere(ok)
    if len(cand) == 0:
        return None
    centres = grid.origin_m + (cand + 0.5) * grid.resolution_m
    return centres[int(np.argmin(np.linalg.norm(centres - base_m, axis=1)))]


@STRATEGIES.register("continuous_exploration")
class ContinuousExploration(ExplorationPlugin):
    """Exploration under continuous connectivity: ``multi_target`` on frontier targets."""

    name = "continuous_exploration"
    Params = ContinuousExplorationParams

    @classmethod
    def initial_state(
        cls, params: Any, scenario: Any, world: World, rng: np.random.Generator
    ) -> TeamState:
        """The base station as for every paradigm, the team in the safe set around it."""
        src = f"{scenario.source}: strategy.params"
        drawn = super().initial_state(params, scenario, world, rng)
        grid = cls._grid(scenario, world)
        mt = controller_params(params, scenario.source)
        conn = mt.connectivity()
        margin = conn.ro_outer_m + grid.resolution_m
        base = clear_base(grid, drawn.fixed[0], margin)
        if base is None:
            raise ScenarioError(
                f"{src}.base_m: no point of the base station's free region is more than "
                f"R'o = {conn.ro_outer_m:g} m from obstacles; use a map with wider free space"
            )
        try:
            q = safe_team(world, scenario.team.n_robots + 1, conn, rng, center_m=base,
                          box_margin_m=conn.ro_m)  # fmt: skip
        except ValueError as exc:
            raise ScenarioError(f"{src}: the team's start around the base station: {exc}") from None
        return TeamState.at_rest(q[1:], fixed=q[:1])

    @classmethod
    def make_policy(cls, params: Any) -> ContinuousPolicy:
        """The policy without its world (:meth:`from_scenario` gives it one)."""
        return ContinuousPolicy(
            controller_params(params, "strategy.params"), None,
            control_period_s=params.control_period_s, stay_s=params.stay_s,
            target_timeout_s=params.target_timeout_s,
        )  # fmt: skip

    @classmethod
    def from_scenario(
        cls, params: Any, scenario: Any, world: World, initial: TeamState, rng: Any
    ) -> ContinuousExploration:
        src = f"{scenario.source}: strategy.params"
        if params.failures.at_s or params.failures.random:
            raise ScenarioError(
                f"{src}.failures: robot failures are not modelled by continuous_exploration; "
                "remove strategy.params.failures"
            )
        if params.scan_steps != 1:
            raise ScenarioError(
                f"{src}.scan_steps: {params.scan_steps}: the controller moves its robots "
                "itself, a scan never holds one; remove scan_steps (or set it to 1)"
            )
        controller_params(params, scenario.source)  # its errors name the scenario
        grid = cls._grid(scenario, world)
        run = super().from_scenario(params, scenario, world, initial, rng)
        run.policy = replace(
            run.policy, world=world, dt_s=scenario.sim.dt_s, seed=int(rng.integers(2**31))
        )
        run.starts_cells = (np.asarray(initial.positions) - grid.origin_m) / grid.resolution_m
        # the sim follows the controller's trajectory of a step (never longer than the top
        # speed allows) in that step
        run.cfg.speed_cells *= 1.0 + 1e-6
        return run
