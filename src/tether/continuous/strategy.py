"""Strategy ``connectivity``: eq. (1) driven only by ``f_lambda`` and an external force.

Each robot obeys ``M dv/dt = -B v + f_lambda + f_ext`` (eq. (1)), where
``f_lambda`` is the generalized connectivity force (App. A, eq. (17)-(18),
:mod:`tether.continuous.gradient`) and ``f_ext`` a bounded external force
standing in for the traveling force of Algorithm 2: nothing, constant
forces, operator goals (a saturated spring to a goal point) or random pulls
(a random direction and magnitude per robot, redrawn every ``hold_s``).

lambda2 and the Fiedler vector come either from an exact eigensolver
(``eigensolver: exact``) or from the decentralized estimator of Yang et al.
(``eigensolver: estimator``, :mod:`tether.continuous.estimation`) running over
the message layer (:mod:`tether.comm`) with optional loss, delay and robot
failures. The motion is integrated by :func:`tether.continuous.dynamics.integrate`.

Example scenario (``src/tether/scenarios/connectivity_town.yaml``)::

    strategy:
      name: connectivity
      params:
        preset: outdoor
        eigensolver: exact
        external: {kind: random, magnitude_n: 3.0, hold_s: 2.0}
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, model_validator

from tether import jit
from tether.comm import CommParams, MessageLayer
from tether.continuous.dynamics import IntegratorParams, integrate
from tether.continuous.estimation import EstimatorParams, FiedlerEstimator, estimate_errors
from tether.continuous.gradient import connectivity_force, exact_force, messages
from tether.continuous.params import TABLE2, ConnectivityParams
from tether.continuous.weights import compute_weights
from tether.errors import ScenarioError
from tether.graph.warm import WarmState
from tether.registry import STRATEGIES
from tether.sim import StepContext, Strategy, TeamState
from tether.world.clearance import ObstacleIndex
from tether.world.world import World

_OUTDOOR = TABLE2["outdoor"]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


class ExternalForce(_Strict):
    """The external force ``f_i`` of eq. (1), bounded by ``magnitude_n`` per robot.

    ``none``; ``constant`` (``forces``: one vector for all robots or one per
    robot); ``goal`` (operator commands: ``robots`` are pulled towards
    ``goals`` by ``gain * (goal - q)``, saturated); ``random`` (each robot a
    uniformly random direction and a magnitude uniform in
    ``[0, magnitude_n]``, redrawn every ``hold_s``; ``planar`` keeps them
    horizontal in 3-D).
    """

    kind: Literal["none", "constant", "goal", "random"] = "none"
    magnitude_n: float = Field(default=1.0, ge=0)
    hold_s: float = Field(default=2.0, gt=0)
    planar: bool = False
    forces: list[list[float]] | None = None
    robots: list[int] = Field(default_factory=list)
    goals: list[list[float]] = Field(default_factory=list)
    gain_n_per_m: float = Field(default=1.0, ge=0)


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


class ConnectivityStrategyParams(_Strict):
    """Parameters of strategy ``connectivity``.

    ``preset`` picks a column of Table 2 (``outdoor`` = empty space and town,
    ``office``, ``experiment`` = Sec. 4.2); any parameter given explicitly
    overrides the preset. The other Table 2 entries (``Rgrid``, ``sigma``,
    ``v_cruise``, ``(x_c, x_M)``, ``Delta t``, ``Rz``) belong to the traveling
    force of Algorithms 1-2 and are not used here.
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
    max_step_fraction: float = Field(default=0.1, gt=0, le=1)
    keep_fraction: float = Field(default=0.5, ge=0, lt=1)
    safeguard: bool = True
    eigensolver: Literal["exact", "estimator"] = "exact"
    #: exact lambda2 from the previous Fiedler vector: ``auto`` = the certified small
    #: dense solver for 17-400 robots (LAPACK when it cannot certify); ``lapack`` = LAPACK
    #: every sub-step (the same eigenpair; trajectories as before it, bit for bit)
    fiedler_method: Literal["auto", "lapack"] = "auto"
    estimator: EstimatorConfig = Field(default_factory=EstimatorConfig)
    external: ExternalForce = Field(default_factory=ExternalForce)

    @model_validator(mode="before")
    @classmethod
    def _apply_preset(cls, data: Any) -> Any:
        if isinstance(data, dict):
            preset = data.get("preset", "outdoor")
            if isinstance(preset, str) and preset in TABLE2:
                data = {**TABLE2[preset], **data}
        return data

    @model_validator(mode="after")
    def _consistent(self) -> ConnectivityStrategyParams:
        try:  # ValueError such as "need 0 < R's < Rs" for radii out of order
            self.connectivity()
            self.integrator()
        except ValueError as exc:
            raise ValueError(
                f"{exc} (R's = rs_inner_m, Rs = rs_m, Ro = ro_m, R'o = ro_outer_m, "
                "Rc = rc_m, R'c = rc_outer_m)"
            ) from None
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

    def integrator(self) -> IntegratorParams:
        width = self.connectivity().transition_width_m
        return IntegratorParams(
            mass_kg=self.mass_kg,
            damping_ns_per_m=self.damping_ns_per_m,
            max_step_m=self.max_step_fraction * width,
            keep_fraction=self.keep_fraction,
        )

    def estimator_params(self) -> EstimatorParams:
        return self.estimator.gains()


def external_force(
    spec: ExternalForce, q: np.ndarray, rng: np.random.Generator, held: np.ndarray | None
) -> np.ndarray:
    """``f_i`` per robot, ``(n, dim)``, never longer than ``spec.magnitude_n``."""
    n, dim = q.shape
    if spec.kind == "none":
        return np.zeros((n, dim))
    if spec.kind == "constant":
        f = np.broadcast_to(np.asarray(spec.forces or [[0.0] * dim], dtype=float), (n, dim))
    elif spec.kind == "goal":
        f = np.zeros((n, dim))
        for robot, goal in zip(spec.robots, spec.goals, strict=True):
            f[robot] = spec.gain_n_per_m * (np.asarray(goal, dtype=float) - q[robot])
    else:
        if held is not None:
            return held
        direction = rng.normal(size=(n, dim))
        if spec.planar and dim == 3:
            direction[:, 2] = 0.0
        direction /= np.maximum(np.linalg.norm(direction, axis=1, keepdims=True), 1e-12)
        f = direction * rng.uniform(0.0, spec.magnitude_n, size=(n, 1))
    norm = np.linalg.norm(f, axis=1, keepdims=True)
    return f * np.minimum(1.0, spec.magnitude_n / np.maximum(norm, 1e-300))


def _check_external(params: ConnectivityStrategyParams, initial: TeamState, src: str) -> None:
    """Robot indices and vector sizes of the external force and failures fit the team."""
    n, dim = initial.n, initial.dim
    ext, field = params.external, f"{src}: strategy.params.external"
    bad = [r for r in ext.robots if not 0 <= r < n]
    if bad:
        raise ScenarioError(f"{field}.robots: {bad[0]} is not a robot index in 0..{n - 1}")
    if ext.kind == "goal" and len(ext.goals) != len(ext.robots):
        raise ScenarioError(
            f"{field}.goals: {len(ext.goals)} goals for {len(ext.robots)} robots; give one "
            "goal per robot"
        )
    if any(len(g) != dim for g in ext.goals):
        raise ScenarioError(f"{field}.goals: each goal needs {dim} coordinates")
    if ext.forces is not None and (
        len(ext.forces) not in (1, n) or any(len(f) != dim for f in ext.forces)
    ):
        raise ScenarioError(
            f"{field}.forces: give one force of {dim} numbers for all robots or one per robot ({n})"
        )
    bad = [r for r in params.estimator.failures if not 0 <= r < n]
    if bad:
        raise ScenarioError(
            f"{src}: strategy.params.estimator.failures: {bad[0]} is not a robot index in "
            f"0..{n - 1}"
        )


def _unsafe_start(lam: float, conn: ConnectivityParams) -> str:
    return (
        f"the initial weighted graph has lambda2 = {lam:.3g} <= lambda2_min = "
        f"{conn.lambda2_min}: place robots within R's = {conn.rs_inner_m} m of a neighbour, "
        f"farther than R'c = {conn.rc_outer_m} m apart and with lines of sight farther than "
        f"R'o = {conn.ro_outer_m} m from obstacles"
    )


@STRATEGIES.register("connectivity")
class ConnectivityStrategy(Strategy):
    """Generalized connectivity force plus an external force (eq. (1), App. A)."""

    name = "connectivity"
    Params = ConnectivityStrategyParams
    #: the exact force is made in the weights' kernel call (a subclass that makes its
    #: force otherwise, multi_target's fused sub-step, turns it off)
    force_with_weights = True

    def __init__(self, params: ConnectivityStrategyParams | None = None) -> None:
        super().__init__()
        self.params = params or ConnectivityStrategyParams()
        self.conn = self.params.connectivity()
        self.integ = self.params.integrator()

    @classmethod
    def from_scenario(
        cls,
        params: ConnectivityStrategyParams,
        scenario: Any,
        world: World,
        initial_state: TeamState,
        rng: np.random.Generator,
    ) -> ConnectivityStrategy:
        _check_external(params, initial_state, scenario.source)
        cls.check_start(params, scenario, world, initial_state)
        return cls(params)

    @staticmethod
    def check_start(
        params: ConnectivityStrategyParams, scenario: Any, world: World, initial: TeamState
    ) -> None:
        """One-line ``ScenarioError`` unless the initial weighted graph is in the safe set."""
        conn = params.connectivity()
        graph = compute_weights(initial.positions, conn, ObstacleIndex.shared(world))
        lam, _ = graph.fiedler()
        if not lam > conn.lambda2_min:
            raise ScenarioError(
                f"{scenario.source}: team.init: {_unsafe_start(lam, conn)}"
                + ("; the scene's layout follows the run seed unless world.params.seed is set"
                   if world.has_obstacles and "seed" not in scenario.world.params
                   and scenario.world.scene in ("town", "office") else "")
            )  # fmt: skip

    # ----------------------------------------------------------------- lifecycle

    def reset(self, world: World, state: TeamState, rng: np.random.Generator) -> None:
        super().reset(world, state, rng)
        self.world = world
        self.obstacles = ObstacleIndex.shared(world)
        self.n = state.n
        self._nu: np.ndarray | None = None
        self._warm = WarmState()  # the large-team eigensolver's factorization, this run only
        self._held: np.ndarray | None = None
        self._held_until = -1.0
        self._current = None
        self._stats = {"substeps": 0, "rejections": 0, "stalls": 0}
        self._min = {"lambda2": np.inf, "distance": np.inf, "clearance": np.inf}
        self._est_err: list[tuple[float, float]] = []
        self.estimator: FiedlerEstimator | None = None
        graph = compute_weights(state.positions, self.conn, self.obstacles)
        lam, nu = graph.fiedler()
        if not lam > self.conn.lambda2_min:
            raise ValueError(_unsafe_start(lam, self.conn))
        self._nu = nu
        if self.params.eigensolver == "estimator":
            e = self.params.estimator
            comm = CommParams(e.loss_probability, e.delay_rounds, dict(e.failures))
            layer = MessageLayer(self.n, comm, rng)
            self.estimator = FiedlerEstimator(self.n, self.params.estimator_params(), layer, rng)
            self.estimator.update(graph, e.warmup_rounds)
        self._observe(state.positions, graph, lam, nu)

    # ----------------------------------------------------------------- evaluation

    def _evaluate(self, q: np.ndarray) -> tuple[float, Any]:
        exact = self.params.eigensolver == "exact" or self.params.safeguard
        method = self.params.fiedler_method
        # with the guess, the kernels solve the eigenpair (and the exact force) in the
        # weights' call: the same bits as the calls below
        with_force = self.force_with_weights and self.estimator is None
        graph = compute_weights(q, self.conn, self.obstacles, guess=self._nu if exact else None,
                                method=method, with_force=with_force)  # fmt: skip
        if exact:
            lam, nu = graph.fiedler(guess=self._nu, state=self._warm, method=method)
        else:
            lam, nu = np.inf, None
        return lam, (graph, lam, nu)

    def _force(self, cache: Any) -> np.ndarray:
        graph, lam, nu = cache
        if self.estimator is None:
            self._nu = nu
            return exact_force(graph, lam, nu, self.conn)
        est = self.estimator
        est.update(graph, self.params.estimator.rounds_per_substep)
        if nu is not None:
            self._nu = nu
        f = connectivity_force(graph, est.lambda2, messages(graph, est.vector), self.conn)
        f[~est.comm.alive()] = 0.0  # a failed robot exerts no force
        return f

    def step(self, ctx: StepContext) -> TeamState:
        self._step = ctx.step
        q, v = ctx.state.positions, ctx.state.velocities
        spec = self.params.external
        if spec.kind == "random" and ctx.t_s >= self._held_until:
            self._held = None
            self._held_until = ctx.t_s + spec.hold_s
        f_ext = external_force(spec, q, ctx.rng, self._held)
        if spec.kind == "random":
            self._held = f_ext
        if self.estimator is not None:
            f_ext = f_ext * self.estimator.comm.alive()[:, None]
        q, v, ev, stats = integrate(
            q, v, ctx.dt_s, self._evaluate, self._force, f_ext, self.integ,
            self.conn.lambda2_min, self._current, box=self.world.bounds_m,
            box_margin_m=self.conn.ro_m,
        )  # fmt: skip
        self._current = ev
        self._stats["substeps"] += stats.substeps
        self._stats["rejections"] += stats.rejections
        self._stats["stalls"] += int(stats.stalled)
        if stats.stalled:
            self.emit("stall", substeps=stats.substeps)
        graph, lam, nu = ev[1]
        self._observe(q, graph, lam, nu)
        return TeamState(q, v)

    # ----------------------------------------------------------------- metrics

    def _observe(self, q: np.ndarray, graph: Any, lam: float, nu: np.ndarray | None) -> None:
        """Track the invariants (exact lambda2, distances, clearances) for ``metrics``."""
        if nu is None and self.n <= 500:
            method = self.params.fiedler_method
            lam, nu = graph.fiedler(guess=self._nu, state=self._warm, method=method)
        if np.isfinite(lam):
            self._min["lambda2"] = min(self._min["lambda2"], float(lam))
        if len(graph.pairs) and jit.enabled():  # the same minimum, compiled
            from tether.continuous.bookkeep_kernels import min_link_distance_kernel

            d_min = min_link_distance_kernel(np.ascontiguousarray(q, dtype=float),
                                             np.ascontiguousarray(graph.pairs))  # fmt: skip
            self._min["distance"] = min(self._min["distance"], d_min)
        elif len(graph.pairs):
            d = np.linalg.norm(q[graph.pairs[:, 0]] - q[graph.pairs[:, 1]], axis=1)
            self._min["distance"] = min(self._min["distance"], float(d.min()))
        if self.obstacles.tree is not None:  # robots the field puts farther are not searched
            low = self._min["clearance"]
            self._min["clearance"] = min(low, self.obstacles.nearest_min(q, low))
        if self.estimator is not None and nu is not None:
            self._est_err.append(estimate_errors(self.estimator, lam, nu))

    def metrics(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "min_lambda2_weighted": self._min["lambda2"],
            "min_robot_distance_m": self._min["distance"],
            "min_obstacle_clearance_m": self._min["clearance"],
            "substeps": self._stats["substeps"],
            "rejected_substeps": self._stats["rejections"],
            "stalls": self._stats["stalls"],
            "eigensolver": self.params.eigensolver,
        }
        if self._est_err:
            err = np.asarray(self._est_err)
            out["estimator_lambda2_rel_error_max"] = float(err[:, 0].max())
            out["estimator_lambda2_rel_error_mean"] = float(err[:, 0].mean())
            out["estimator_vector_error_max"] = float(err[:, 1].max())
        if self.estimator is not None:
            out["message_delivery_ratio"] = self.estimator.comm.delivery_ratio
        return {k: (None if isinstance(v, float) and not np.isfinite(v) else v)
                for k, v in out.items()}  # fmt: skip
