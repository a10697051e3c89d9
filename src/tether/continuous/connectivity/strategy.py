"""Strategy ``connectivity``: eq. (1) driven only by ``f_lambda`` and an external force.

Each robot obeys ``M dv/dt = -B v + f_lambda + f_ext`` (eq. (1)), where
``f_lambda`` is the generalized connectivity force (App. A, eq. (17)-(18),
:mod:`tether.continuous.connectivity.gradient`) and ``f_ext`` a bounded external force
standing in for the traveling force of Algorithm 2: nothing, constant
forces, operator goals (a saturated spring to a goal point) or random pulls
(a random direction and magnitude per robot, redrawn every ``hold_s``).

lambda2 and the Fiedler vector come either from an exact eigensolver
(``eigensolver: exact``) or from the decentralized estimator of Yang et al.
(``eigensolver: estimator``, :mod:`tether.continuous.connectivity.estimation`) running over
the message layer (:mod:`tether.comm`) with optional loss, delay and robot
failures. The motion is integrated by :func:`tether.continuous.connectivity.dynamics.integrate`.

Example scenario (``src/tether/scenarios/connectivity_town.yaml``)::

    strategy:
      name: connectivity
      params:
        preset: outdoor
        eigensolver: exact
        external: {kind: random, magnitude_n: 3.0, hold_s: 2.0}
"""

from __future__ import annotations

from typing import Any

import numpy as np

from tether import jit
from tether.comm import CommParams, MessageLayer
from tether.continuous.connectivity.dynamics import (
    IntegrationStats,
    StepMemory,
    displacement_step,
    integrate,
)
from tether.continuous.connectivity.estimation import FiedlerEstimator, estimate_errors
from tether.continuous.connectivity.external import check_external, external_force
from tether.continuous.connectivity.gradient import connectivity_force, exact_force, messages
from tether.continuous.connectivity.params import ConnectivityParams
from tether.continuous.connectivity.potential import potential
from tether.continuous.connectivity.strategy_params import (
    ConnectivityStrategyParams,
    ContinuousParams,
)
from tether.continuous.connectivity.weights import compute_weights
from tether.errors import ScenarioError
from tether.graph.warm import WarmState
from tether.registry import STRATEGIES
from tether.sim import StepContext, Strategy, TeamState
from tether.world.clearance import ObstacleIndex
from tether.world.world import World


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

    def __init__(self, params: ContinuousParams | None = None) -> None:
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
        check_external(params.external, params.estimator.failures, initial_state, scenario.source)
        cls.check_start(params, scenario, world, initial_state)
        return cls(params)

    @staticmethod
    def check_start(
        params: ContinuousParams, scenario: Any, world: World, initial: TeamState
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
        self._f_ext: np.ndarray | None = None
        self._current = None
        self._memory = StepMemory()
        self._run = IntegrationStats()
        self._period = IntegrationStats()
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

    # ------------------------------------------- the integrator's System protocol

    def evaluate(self, q: np.ndarray) -> tuple[float, Any]:
        """The exact weighted lambda2 of ``q`` (``inf`` when nothing needs it) and the cache
        the forces use: ``(graph, lambda2, Fiedler vector)``."""
        exact = self.params.eigensolver == "exact" or self.params.guard != "off"
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

    def connectivity_force(self, cache: Any) -> np.ndarray:
        """``f_lambda`` (eq. (17)) at the cached configuration; the estimator's current
        estimates when it runs (a failed robot exerts no force)."""
        graph, lam, nu = cache
        if self.estimator is None:
            return exact_force(graph, lam, nu, self.conn)
        est = self.estimator
        f = connectivity_force(graph, est.lambda2, messages(graph, est.vector), self.conn)
        f[~est.comm.alive()] = 0.0
        return f

    def forces(self, q: np.ndarray, v: np.ndarray, cache: Any) -> tuple:
        """``(f_lambda + f_i, f_lambda, displacement step)`` at ``(q, v)``."""
        f_lambda = self.connectivity_force(cache)
        total = f_lambda + self._f_ext
        return total, f_lambda, displacement_step(v, total, self.integ.mass_kg,
                                                  self.integ.max_step_m)  # fmt: skip

    def accept(self, q: np.ndarray, v: np.ndarray, cache: Any) -> bool:
        """A sub-step ended at ``q``: keep its Fiedler vector (the next solve's guess) and
        advance the estimator's rounds (then the force changes: True)."""
        graph, _, nu = cache
        if nu is not None:
            self._nu = nu
        if self.estimator is None:
            return False
        self.estimator.update(graph, self.params.estimator.rounds_per_substep)
        return True

    def neighbours(self, cache: Any) -> np.ndarray:
        return cache[0].pairs

    def potential(self, lambda2: float) -> float:
        return potential(lambda2, self.conn)[0]

    # ----------------------------------------------------------------- one period

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
        self._f_ext = f_ext
        q, v, ev, stats = self.integrate(q, v, ctx.dt_s, self)
        graph, lam, nu = ev[1]
        self._observe(q, graph, lam, nu)
        return TeamState(q, v)

    def integrate(
        self, q: np.ndarray, v: np.ndarray, dt_s: float, system: Any
    ) -> tuple[np.ndarray, np.ndarray, tuple[float, Any], IntegrationStats]:
        """One control period of eq. (1) for ``system``; its statistics are kept."""
        q, v, ev, stats = integrate(
            q, v, dt_s, system, self.integ, self.conn.lambda2_min, self._current,
            box=self.world.bounds_m, box_margin_m=self.conn.ro_m, memory=self._memory,
        )  # fmt: skip
        self._current = ev
        self._period = stats
        self._run.add(stats)
        if stats.stalled:
            self.emit("stall", substeps=stats.substeps)
        return q, v, ev, stats

    # ----------------------------------------------------------------- metrics

    def _observe(self, q: np.ndarray, graph: Any, lam: float, nu: np.ndarray | None) -> None:
        """Track the invariants (exact lambda2, distances, clearances) for ``metrics``."""
        if nu is None and self.n <= 500:
            method = self.params.fiedler_method
            lam, nu = graph.fiedler(guess=self._nu, state=self._warm, method=method)
        if np.isfinite(lam):
            self._min["lambda2"] = min(self._min["lambda2"], float(lam))
        if len(graph.pairs) and jit.enabled():  # the same minimum, compiled
            from tether.continuous.connectivity.bookkeep_kernels import min_link_distance_kernel

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

    def step_values(self) -> dict[str, Any]:
        """Per control period: the largest speed and acceleration, and running totals of
        what the integrator and the guard did (totals survive ``record_every``)."""
        p, r = self._period, self._run
        return {
            "max_speed_mps": p.max_speed_mps,
            "max_accel_mps2": p.max_accel_mps2,
            "substeps": p.substeps,
            "rejected_substeps_total": r.rejections,
            "guard_interventions_total": r.guard_interventions,
            "safe_set_exits_total": r.safe_set_exits,
            "energy_added_j_total": r.energy_added_j,
        }

    def controller_success(self) -> bool | None:
        """The invariants held by the controller alone: no guard intervention, no step
        outside the safe set, every sub-step within the step rule (``None`` with the guard
        off: not measured)."""
        r = self._run
        if self.params.guard == "off":
            return None
        return r.guard_interventions == 0 and r.safe_set_exits == 0 and r.tolerance_misses == 0

    def metrics(self) -> dict[str, Any]:
        r = self._run
        out: dict[str, Any] = {
            "min_lambda2_weighted": self._min["lambda2"],
            "min_robot_distance_m": self._min["distance"],
            "min_obstacle_clearance_m": self._min["clearance"],
            "guard": self.params.guard,
            "controller_success": self.controller_success(),
            "guard_interventions": r.guard_interventions,
            "safe_set_exits": r.safe_set_exits,
            "stalls": r.stalls,
            "substeps": r.substeps,
            "rejected_substeps": r.rejections,
            "tolerance_misses": r.tolerance_misses,
            "min_substep_s": r.min_step_s,
            "max_speed_mps": r.max_speed_mps,
            "speed_bound_mps": self.integ.robot.max_speed_mps,
            "max_accel_mps2": r.max_accel_mps2,
            "energy_added_j": r.energy_added_j,
            "energy_net_j": r.energy_net_j,
            "speed_limit_work_j": r.speed_limit_work_j,
            "box_contacts": r.box_contacts,
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
