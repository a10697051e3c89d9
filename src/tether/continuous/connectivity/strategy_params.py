"""Parameters of the ``connectivity`` strategy: Table 2, the robot model, the guard, the solver.

``preset`` picks a column of Table 2 of the continuous-connectivity paper; any parameter
given explicitly overrides it. The robot model (mass, damping, speed bound) and the
guard are explained in :mod:`tether.continuous.connectivity.robot` and
:mod:`tether.continuous.connectivity.dynamics`; ``docs/continuous.md`` lists every key with its
default and why.
"""

from __future__ import annotations

from typing import Any, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

from tether.continuous.connectivity.dynamics import GUARDS, IntegratorParams
from tether.continuous.connectivity.estimation import EstimatorParams
from tether.continuous.connectivity.external import ExternalForce
from tether.continuous.connectivity.params import TABLE2, TRAVEL_TABLE2, ConnectivityParams
from tether.continuous.connectivity.robot import RobotModel

_OUTDOOR = TABLE2["outdoor"]

#: the platform's top speed is this many times the preset's cruise speed unless given
SPEED_BOUND_OVER_CRUISE = 2.0


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


MAX_ROUNDS = 10_000  # message rounds per sub-step (estimator) or control step (multi_target)
MAX_WARMUP_ROUNDS = 1_000_000  # about 70 s for 35 robots
MAX_DELAY_ROUNDS = 1_000


class EstimatorConfig(EstimatorParams):
    """Decentralized estimator (its gains), rounds and message-layer faults."""

    model_config = ConfigDict(extra="forbid", frozen=False, allow_inf_nan=False)

    # the caps bound the work and the messages held in flight (about 20 kB per round of
    # delay for 35 robots); far above the paper's few rounds
    rounds_per_substep: int = Field(default=20, ge=1, le=MAX_ROUNDS)
    warmup_rounds: int = Field(default=3000, ge=0, le=MAX_WARMUP_ROUNDS)
    loss_probability: float = Field(default=0.0, ge=0, lt=1)
    delay_rounds: int = Field(default=0, ge=0, le=MAX_DELAY_ROUNDS)
    failures: dict[int, int] = Field(default_factory=dict)


class ContinuousParams(_Strict):
    """Parameters of the connectivity force, the robot and the integrator, shared by
    ``connectivity`` and ``multi_target``.

    ``preset`` picks a column of Table 2 (``outdoor`` = empty space and town,
    ``office``, ``experiment`` = Sec. 4.2); any parameter given explicitly
    overrides the preset. The other Table 2 entries (``Rgrid``, ``sigma``,
    ``v_cruise``, ``(x_c, x_M)``, ``Delta t``, ``Rz``) belong to the traveling
    force of Algorithms 1-2; ``v_cruise`` of the preset sets the default speed bound.
    """

    preset: Literal["outdoor", "office", "experiment"] = "outdoor"
    rs_inner_m: float = Field(default=_OUTDOOR["rs_inner_m"], gt=0)
    rs_m: float = Field(default=_OUTDOOR["rs_m"], gt=0)
    ro_m: float = Field(default=_OUTDOOR["ro_m"], gt=0)
    ro_outer_m: float = Field(default=_OUTDOOR["ro_outer_m"], gt=0)
    rc_m: float = Field(default=_OUTDOOR["rc_m"], gt=0)
    rc_outer_m: float = Field(default=_OUTDOOR["rc_outer_m"], gt=0)
    lambda2_min: float = Field(default=_OUTDOOR["lambda2_min"], ge=0)
    lambda2_null: float = Field(default=_OUTDOOR["lambda2_null"], gt=0)
    potential_gain_n: float = Field(default=1.0, gt=0)
    mass_kg: float = Field(default=1.0, gt=0)
    damping_ns_per_m: float = Field(default=2.0, ge=0)
    max_speed_mps: float | None = Field(
        default=None, gt=0,
        description="the platform's top speed; default twice the preset's cruise speed",
    )  # fmt: skip
    speed_damping_n: float = Field(default=0.25, ge=0)
    max_step_fraction: float = Field(default=0.1, gt=0, le=1)
    guard: Literal["enforce", "detect", "off"] = "detect"
    keep_fraction: float = Field(default=0.5, ge=0, lt=1)
    eigensolver: Literal["exact", "estimator"] = "exact"
    #: exact lambda2 from the previous Fiedler vector: ``auto`` = the certified small
    #: dense solver for 17-400 robots (LAPACK when it cannot certify); ``lapack`` = LAPACK
    #: every sub-step (the same eigenpair)
    fiedler_method: Literal["auto", "lapack"] = "auto"
    estimator: EstimatorConfig = Field(default_factory=EstimatorConfig)

    @model_validator(mode="before")
    @classmethod
    def _apply_preset(cls, data: Any) -> Any:
        if isinstance(data, dict):
            if "safeguard" in data:
                raise ValueError(
                    "safeguard: unknown key; the guard is set by guard: detect (count steps "
                    "that leave the safe set, the default), enforce (veto them) or off"
                )
            preset = data.get("preset", "outdoor")
            if isinstance(preset, str) and preset in TABLE2:
                data = {**TABLE2[preset], **data}
        return data

    @model_validator(mode="after")
    def _consistent(self) -> ContinuousParams:
        try:  # ValueError such as "need 0 < R's < Rs" for radii out of order
            self.connectivity()
        except ValueError as exc:
            raise ValueError(
                f"{exc} (R's = rs_inner_m, Rs = rs_m, Ro = ro_m, R'o = ro_outer_m, "
                "Rc = rc_m, R'c = rc_outer_m)"
            ) from None
        self.integrator()
        return self

    def connectivity(self) -> ConnectivityParams:
        return ConnectivityParams(
            rs_inner_m=self.rs_inner_m,
            rs_m=self.rs_m,
            ro_m=self.ro_m,
            ro_outer_m=self.ro_outer_m,
            rc_m=self.rc_m,
            rc_outer_m=self.rc_outer_m,
            lambda2_min=self.lambda2_min,
            lambda2_null=self.lambda2_null,
            potential_gain=self.potential_gain_n,
        )

    def cruise_speed_mps(self) -> float:
        """The preset's cruise speed (``multi_target`` overrides it with its own)."""
        return TRAVEL_TABLE2[self.preset]["v_cruise_mps"]

    def speed_bound_mps(self) -> float:
        """``max_speed_mps``, or twice the cruise speed when it is not given."""
        if self.max_speed_mps is not None:
            return self.max_speed_mps
        return SPEED_BOUND_OVER_CRUISE * self.cruise_speed_mps()

    def robot(self) -> RobotModel:
        return RobotModel(
            mass_kg=self.mass_kg,
            damping_ns_per_m=self.damping_ns_per_m,
            max_speed_mps=self.speed_bound_mps(),
            speed_damping_n=self.speed_damping_n,
        )

    def integrator(self) -> IntegratorParams:
        width = self.connectivity().transition_width_m
        assert self.guard in GUARDS
        return IntegratorParams(
            robot=self.robot(),
            max_step_m=self.max_step_fraction * width,
            tolerance_m=0.1 * self.max_step_fraction * width,
            guard=self.guard,
            keep_fraction=self.keep_fraction,
        )

    def estimator_params(self) -> EstimatorParams:
        return self.estimator.gains()


class ConnectivityStrategyParams(ContinuousParams):
    """Parameters of strategy ``connectivity``: :class:`ContinuousParams` and the external
    force ``f_i`` of eq. (1) (``multi_target``'s is Algorithm 2's traveling force)."""

    external: ExternalForce = Field(default_factory=ExternalForce)
