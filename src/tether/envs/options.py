"""The options of an environment: reward weights and observation shape, checked up front.

Every option is a keyword of :func:`tether.envs.parallel_env` (and of the other forms).
A wrong name or value is a ``ValueError`` / ``TypeError`` of one line that names the
option and what it accepts.
"""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator

from tether.suggest import did_you_mean

#: reward terms and what one unit of each is (docs/how-to/environments.md, "Rewards")
TERMS: dict[str, str] = {
    "progress": "task progress this step (metres of leader path, metres closer to the "
    "goals or current targets, percent of the map explored)",
    "targets": "targets completed this step",
    "connected": "1 if the link graph (base station included) is connected, else 0",
    "disconnected": "1 if the link graph is not connected, else 0",
    "lambda2": "algebraic connectivity of the unweighted link graph",
    "margin": "bottleneck link margin: 1 - (longest link of a shortest spanning tree) / "
    "link range; 0 when disconnected",
    "base": "fraction of robots connected to a base station (0 without one)",
    "collisions": "robot pairs closer than sim.collision_distance_m",
    "blocked": "robots whose commanded move an obstacle or the world's box shortened",
    "clearance": "robots closer than clearance_m to an obstacle",
}

#: default weights: reward = sum(weight * term)
DEFAULT_WEIGHTS: dict[str, float] = {
    "progress": 1.0,
    "targets": 10.0,
    "connected": 0.0,
    "disconnected": -1.0,
    "lambda2": 0.0,
    "margin": 0.1,
    "base": 0.1,
    "collisions": -1.0,
    "blocked": -0.1,
    "clearance": 0.0,
}


class EnvOptions(BaseModel):
    """Options shared by every form of the environment (see docs/how-to/environments.md)."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)

    reward: dict[str, float] = Field(default_factory=dict)
    max_neighbours: int = Field(default=6, ge=0, le=64)
    map_patch_cells: int = Field(default=0, ge=0, le=8)
    max_speed_mps: float | None = Field(default=None, gt=0, le=1e4)
    clearance_m: float | None = Field(default=None, ge=0, le=1e4)
    coverage_cell_m: float | None = Field(default=None, gt=0, le=1e3)
    record: bool = False

    @field_validator("reward")
    @classmethod
    def _known_terms(cls, value: dict[str, float]) -> dict[str, float]:
        for name in value:
            if name not in TERMS:
                raise ValueError(
                    f"unknown reward term {name!r}{did_you_mean(name, list(TERMS))}; "
                    f"expected some of: {', '.join(TERMS)}"
                )
        return value

    def weights(self) -> dict[str, float]:
        """The reward weights: the defaults, overridden by ``reward``."""
        return {**DEFAULT_WEIGHTS, **self.reward}


def env_options(options: dict[str, Any]) -> EnvOptions:
    """:class:`EnvOptions` from keyword options; a one-line ``ValueError`` otherwise."""
    try:
        return EnvOptions(**options)
    except ValidationError as exc:
        err = exc.errors()[0]
        where = ".".join(str(p) for p in err["loc"]) or "options"
        if err["type"] == "extra_forbidden":
            name = str(err["loc"][0])
            raise TypeError(
                f"unknown environment option {name!r}"
                f"{did_you_mean(name, list(EnvOptions.model_fields))}; expected some of: "
                f"{', '.join(EnvOptions.model_fields)}"
            ) from None
        msg = err["msg"].removeprefix("Value error, ")
        raise ValueError(f"environment option {where}: {msg} (got {err.get('input')!r})") from None
