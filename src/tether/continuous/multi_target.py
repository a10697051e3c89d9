"""Strategy ``multi_target``: decentralized multi-target exploration under continuous connectivity.

The continuous-connectivity paper's own contribution (Secs. 3-4): every robot
visits its own online list of targets while the weighted graph stays connected
at every instant. Each control period:

1. message rounds over the links of the weighted graph: the prime-traveler
   election (:mod:`.election`) and the consensus estimate of the prime's
   efficiency, eq. (13) (:mod:`.consensus`);
2. Algorithm 1 (:mod:`.roles`): targets, paths, roles;
3. eq. (1) integrated with adaptive sub-steps (:mod:`.dynamics`), the traveling
   force of Algorithm 2 re-evaluated at every sub-step (:func:`traveling_forces`:
   eqs. (3)-(8), (14)-(15)), the connectivity force of App. A as in the
   ``connectivity`` strategy, and a guard that keeps anchors within ``Rz``.

Decisions where the paper is silent are listed in ``docs/multi_target.md``.
"""

from __future__ import annotations

from functools import cache
from types import SimpleNamespace
from typing import Any

import numpy as np

from tether import floats, jit
from tether.comm import CommParams, MessageLayer
from tether.continuous.consensus import EfficiencyConsensus
from tether.continuous.dynamics import integrate
from tether.continuous.election import Election
from tether.continuous.multi_target_checks import check_planning_grid, target_book
from tether.continuous.multi_target_params import MultiTargetParams
from tether.continuous.placement import safe_team
from tether.continuous.recruit import HelpFlood, RequestDepth, help_force
from tether.continuous.reference_filter import ReferenceFilter
from tether.continuous.roles import ANCHOR, CONNECTOR, PRIME, ROLE_NAMES, SECONDARY, RolePlanner
from tether.continuous.strategy import ConnectivityStrategy
from tether.continuous.substep import fused_total_force
from tether.continuous.targets import TargetBook, outside_heights
from tether.continuous.travel import (
    alignment,
    anchor_force,
    efficiency,
    rho,
    travel_force,
)
from tether.errors import ScenarioError
from tether.registry import STRATEGIES
from tether.sim import StepContext, TeamState
from tether.world.world import World


def traveling_forces(
    q: np.ndarray,
    v: np.ndarray,
    f_lambda: np.ndarray,
    planner: RolePlanner,
    lambda_hat: np.ndarray,
    p: MultiTargetParams,
    anchors: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """``f_i`` of Algorithm 2 for every robot, ``(n, dim)``.

    Connectors 0; the prime ``f_travel`` (eq. (3)); secondaries
    ``rho(Theta(f_lambda_i, f_travel_i), Lambda_hat_i, sigma) f_travel`` (eqs.
    (4), (8), (14), (15)); anchors ``f_anchor`` (eq. (7)). Robot ``i``'s row
    uses only its own state, path and target, ``f_lambda_i`` and ``Lambda_hat_i``.
    ``anchors``: the anchored robots and their targets, if the caller has them.
    """
    if anchors is None:
        held = np.flatnonzero(planner.anchored())
        anchors = held, _targets(planner, held, q.shape[1])
    if jit.enabled():
        return _traveling_forces_kernel(q, v, f_lambda, planner, lambda_hat, p, anchors)
    f = np.zeros_like(q)
    role = planner.role
    trav, paths = planner.path_set()  # the travelers: prime and secondaries on their way
    if len(trav):
        ps = paths.states(q[trav], p.v_cruise_mps)
        ft = travel_force(q[trav], v[trav], ps, kp=p.kp_n_per_m, kv=p.kv_ns_per_m,
                          mass_kg=p.mass_kg, damping_ns_per_m=p.damping_ns_per_m,
                          max_force_n=p.max_travel_force_n)  # fmt: skip
        sec = role[trav] == SECONDARY
        scale = np.ones(len(trav))
        scale[sec] = rho(alignment(f_lambda[trav[sec]], ft[sec]), lambda_hat[trav[sec]], p.sigma)
        f[trav] = scale[:, None] * ft
    held, targets = anchors
    if len(held):
        f[held] = anchor_force(q[held], targets, p.rz_m, p.kz_n)
    return f


def _targets(planner: RolePlanner, robots: np.ndarray, dim: int) -> np.ndarray:
    return planner.targets_of(robots) if len(robots) else np.zeros((0, dim))


@cache
def _kernels() -> SimpleNamespace:
    """:mod:`tether.continuous.pair_kernels` and :mod:`~tether.continuous.bookkeep_kernels`,
    imported on first use (they load numba; an import statement per call costs
    microseconds)."""
    from tether.continuous import bookkeep_kernels, pair_kernels

    return SimpleNamespace(
        any_row_beyond=pair_kernels.any_row_beyond,
        travel_stretch_kernel=bookkeep_kernels.travel_stretch_kernel,
    )


def _anchor_leaves(q: np.ndarray, held: np.ndarray, targets: np.ndarray, rz_m: float) -> bool:
    """True if an anchored robot ``held[k]`` is ``Rz`` or farther from ``targets[k]``.

    ``q`` is ``(n, dim)``, ``targets`` ``(len(held), dim)``. With the kernels, one
    compiled call (:func:`tether.continuous.pair_kernels.any_row_beyond`, the same
    distances as ``numpy.linalg.norm``); the numpy test otherwise (the reference).
    """
    if jit.enabled():
        return bool(_kernels().any_row_beyond(q, held, targets, rz_m))
    return bool(np.any(np.linalg.norm(q[held] - targets, axis=1) >= rz_m))


def _traveling_forces_kernel(
    q: np.ndarray,
    v: np.ndarray,
    f_lambda: np.ndarray,
    planner: RolePlanner,
    lambda_hat: np.ndarray,
    p: MultiTargetParams,
    anchors: tuple[np.ndarray, np.ndarray],
) -> np.ndarray:
    """:func:`traveling_forces` in one call of the compiled kernel (same bits)."""
    from tether.continuous.tracking_kernels import traveling_kernel

    return traveling_kernel(np.ascontiguousarray(q), np.ascontiguousarray(v),
                            np.ascontiguousarray(f_lambda),
                            *travel_args(planner, lambda_hat, p, anchors),
                            *travel_gains(p))  # fmt: skip


def travel_args(
    planner: RolePlanner,
    lambda_hat: np.ndarray,
    p: MultiTargetParams,
    anchors: tuple[np.ndarray, np.ndarray],
) -> tuple:
    """The traveling kernel's arguments after ``f_lambda`` that a control period fixes.

    The travelers, which of them are secondaries, ``Lambda_hat``, the anchored robots
    and their targets, the paths' kernel arrays, ``v_cruise``, the tie width and
    :func:`~tether.world.clearance.einsum_order`.
    """
    from tether.continuous.tracking import TIE_M
    from tether.world.clearance import einsum_order

    trav, paths = planner.path_set()
    trav = trav.astype(np.int64)
    held, targets = anchors[0].astype(np.int64), anchors[1]
    path = paths.kernel_args() if len(trav) else _NO_PATHS
    return (trav, planner.role[trav] == SECONDARY, np.ascontiguousarray(lambda_hat, dtype=float),
            held, np.ascontiguousarray(targets, dtype=float), path, float(p.v_cruise_mps), TIE_M,
            einsum_order())  # fmt: skip


def travel_gains(p: MultiTargetParams) -> tuple[float, ...]:
    """``(kp, kv, mass, damping, max_force, sigma, Rz, kz)`` as the traveling kernel takes them."""
    return (p.kp_n_per_m, p.kv_ns_per_m, p.mass_kg, p.damping_ns_per_m, p.max_travel_force_n,
            p.sigma, p.rz_m, p.kz_n)  # fmt: skip


_ROLE_ARRAY = np.array(ROLE_NAMES)  # role names by role code

_i0, _f1, _f2 = np.zeros(1, np.int64), np.zeros(0), np.zeros((0, 3))
#: path arguments of the traveling kernel when nobody travels (the types of a PathSet's)
_NO_PATHS = (_i0, _f2, _f2, _f1, _f1, _f1, _f2, _f2, _f2, _f2, _f1, _f1, _f1, _i0[:0])


@STRATEGIES.register("multi_target")
class MultiTargetStrategy(ConnectivityStrategy):
    """Decentralized multi-target exploration (Algorithms 1-2) on the connectivity force."""

    name = "multi_target"
    Params = MultiTargetParams
    force_with_weights = False  # the fused sub-step (continuous/substep.py) makes the force

    def __init__(self, params: MultiTargetParams, book: TargetBook) -> None:
        super().__init__(params)
        self.params: MultiTargetParams = params
        self.targets = book

    @classmethod
    def initial_state(
        cls, params: MultiTargetParams, scenario: Any, world: World, rng: np.random.Generator
    ) -> TeamState | None:
        """A random safe team (``start``) unless ``team.init`` gives positions."""
        if scenario.team.init.kind == "positions":
            return None
        s = params.start
        why = None if s.center_m is not None else outside_heights(s.height_m, world)
        if why is not None:
            raise ScenarioError(f"{scenario.source}: strategy.params.start.height_m: {why}")
        try:
            q = safe_team(world, scenario.team.n_robots, params.connectivity(), rng,
                          margin_m=s.margin_m, center_m=s.center_m,
                          box_margin_m=params.ro_m,
                          height_m=tuple(s.height_m) if s.height_m else None)  # fmt: skip
        except ValueError as exc:
            raise ScenarioError(f"{scenario.source}: strategy.params.start: {exc}") from None
        return TeamState.at_rest(q)

    @classmethod
    def from_scenario(
        cls,
        params: MultiTargetParams,
        scenario: Any,
        world: World,
        initial: TeamState,
        rng: np.random.Generator,
    ) -> MultiTargetStrategy:
        cls.check_start(params, scenario, world, initial)
        check_planning_grid(params.r_grid_m, scenario, world)  # built at reset; validate sees it
        book = target_book(params.targets, scenario, world, initial.n, rng)
        return cls(params, book)

    # -- lifecycle ---------------------------------------------------------------------
    def reset(self, world: World, state: TeamState, rng: np.random.Generator) -> None:
        super().reset(world, state, rng)
        for robot, queue in enumerate(self.targets.queues):  # the run folder keeps them
            for z in queue:
                self._record_target(robot, z)
        p, n = self.params, state.n
        comm = CommParams(p.messages.loss_probability, p.messages.delay_rounds)
        self.election = Election(n, MessageLayer(n, comm, rng))
        self.consensus = EfficiencyConsensus(n, MessageLayer(n, comm, rng), p.k_lambda_per_s)
        self.help = HelpFlood(n, state.dim, MessageLayer(n, comm, rng))
        self._helpers = np.zeros(0, dtype=int)
        self._depth = RequestDepth(p.help_after_s, p.help_max_hops, p.help_until)
        self._help_requests = 0
        self._helper_s = 0.0
        self.planner = RolePlanner(
            world, self.targets, r_grid_m=p.r_grid_m, rz_m=p.rz_m,
            inflate_m=p.inflate_m or 0.5 * (p.ro_m + p.ro_outer_m),
            r_gamma_m=p.r_gamma_m or p.rz_m, stall_timeout_s=p.stall_timeout_s, emit=self.emit,
            replan_stalled_s=p.replan_stalled_s,
        )  # fmt: skip
        self.planner.start_up(state.positions)
        self.filter: ReferenceFilter | None = None  # made at the first step (it needs dt)
        self._t_s = 0.0
        self._completion: float | None = 0.0 if self.planner.done() else None
        self._travelled = np.zeros(n)
        self._stretch = 0.0
        self._lambda_sum, self._lambda_count = 0.0, 0
        self._max_primes = 0
        self._elections = 0
        self._filter_dev = 0.0
        self._prime_eff = 1.0
        self._held: tuple[np.ndarray, np.ndarray] | None = None
        self._last_links: np.ndarray | None = None
        self._current = self._evaluate(state.positions)

    def _anchors(self) -> tuple[np.ndarray, np.ndarray]:
        """The anchored robots and their targets (fixed while a period is integrated)."""
        if self._held is not None:
            return self._held
        held = np.flatnonzero(self.planner.anchored())
        return held, _targets(self.planner, held, self.world.dim)

    def _evaluate(self, q: np.ndarray) -> tuple[float, Any]:
        lam, cache = super()._evaluate(q)
        held, targets = self._anchors()
        if len(held) and _anchor_leaves(q, held, targets, self.params.rz_m):
            return -np.inf, cache  # an anchor would leave its ball: reject the sub-step
        return lam, cache

    # -- one control period ------------------------------------------------------------
    def _links(self) -> np.ndarray:
        """The links of the weighted graph; the same array object while they do not change
        (the message layer then reuses its link bookkeeping)."""
        graph = self._current[1][0]
        links = graph.pairs[graph.pair_factor > 0]
        if self._last_links is not None and np.array_equal(self._last_links, links):
            return self._last_links
        self._last_links = links
        return links

    def _communicate(self, q: np.ndarray, v: np.ndarray, t_s: float, dt_s: float) -> None:
        p, pl = self.params, self.planner
        wants = pl.update(q, t_s)
        robots, paths = pl.path_set()
        states = paths.states(q[robots], p.v_cruise_mps)
        if p.election_criterion == "path_length":
            crit = np.full(len(q), np.inf)
            crit[robots] = states.remaining_m
        else:
            crit = pl.distance_to_target(q)
        links = self._links()
        rounds = p.messages.rounds_per_step
        for _ in range(rounds):
            out = self.election.round(links, pl.role == SECONDARY, crit, pl.role == SECONDARY,
                                      wants)  # fmt: skip
            for epoch, host in out.opened:
                self.emit("election_open", host, t_s=t_s, epoch=epoch)
            for epoch, host, winner in out.decided:
                self._elections += 1
                self.emit("election", host, t_s=t_s, epoch=epoch, winner=winner,
                          candidates=self.election.candidates.get(epoch, []))  # fmt: skip
                pl.abdicate(host, t_s)
            for w in out.became_prime:
                pl.set_role(w, PRIME, t_s)
            for w in out.declined:
                self.emit("election_declined", w, t_s=t_s)
        prime = int(np.flatnonzero(pl.role == PRIME)[0]) if (pl.role == PRIME).any() else -1
        self._prime_eff = 1.0  # a prime at its target (no path) tracks perfectly
        where = np.flatnonzero(robots == prime)
        if len(where):  # eqs. (11)-(12)
            k = int(where[0])
            err = (1 - p.alpha_lambda) * floats.norm(states.velocity_mps[k] - v[prime]) \
                + p.alpha_lambda * states.distance_m[k]  # fmt: skip
            band = (p.xc_frac * p.v_cruise_mps, p.xm_frac * p.v_cruise_mps)
            self._prime_eff = float(efficiency(np.array([err]), *band)[0])
        for _ in range(rounds):
            self.consensus.round(links, dt_s / rounds, prime, self._prime_eff)
        self._recruit(q, links, prime, t_s, dt_s)

    def _recruit(
        self, q: np.ndarray, links: np.ndarray, prime: int, t_s: float, dt_s: float
    ) -> None:
        """A stalled prime's help request, flooded; who follows whom (:mod:`.recruit`)."""
        p, pl = self.params, self.planner
        stalled_s = pl.stalled_s(prime, t_s) if prime >= 0 else 0.0
        fresh = self._depth.depth == 0
        depth, change = self._depth.update(prime, stalled_s)
        if change == "requested":
            self._help_requests += fresh
            self.emit("help_requested", prime, t_s=t_s, hops=depth)
        elif change == "ended":
            self.emit("help_ended", prime, t_s=t_s)
        for _ in range(p.messages.rounds_per_step):
            self.help.round(links, q, prime, depth)
        self._helpers = self.help.helpers((pl.role == CONNECTOR) | (pl.role == SECONDARY))
        self._helper_s += len(self._helpers) * dt_s

    def step(self, ctx: StepContext) -> TeamState:
        self._step = ctx.step
        q, v = ctx.state.positions, ctx.state.velocities
        self._communicate(q, v, ctx.t_s, ctx.dt_s)
        self._held = self._anchors()  # roles and targets do not change until the next period

        p, helpers = self.params, self._helpers
        parents_m = self.help.parent_m[helpers]

        def helped(qq: np.ndarray, vv: np.ndarray, f: np.ndarray, f_lambda: np.ndarray
                   ) -> np.ndarray:  # fmt: skip
            """Recruited robots follow their parent instead (a secondary's ``f_i`` too);
            with ``help_lambda_factor`` their ``f_lambda`` is scaled by it
            (:mod:`~tether.continuous.recruit`)."""
            f[helpers] = help_force(qq[helpers], vv[helpers], parents_m, keep_m=p.rs_inner_m,
                                    kp=p.kp_n_per_m, kv=p.kv_ns_per_m,
                                    max_force_n=p.max_travel_force_n)  # fmt: skip
            if p.help_lambda_factor is not None:
                f[helpers] -= (1.0 - p.help_lambda_factor) * f_lambda[helpers]
            return f

        def external(qq: np.ndarray, vv: np.ndarray, f_lambda: np.ndarray) -> np.ndarray:
            f = traveling_forces(qq, vv, f_lambda, self.planner, self.consensus.estimate, p,
                                 anchors=self._held)  # fmt: skip
            return helped(qq, vv, f, f_lambda) if len(helpers) else f

        fused = None
        if jit.enabled() and self.estimator is None:  # one compiled call per sub-step

            def adjust(qq: np.ndarray, vv: np.ndarray, f_lambda: np.ndarray,
                       f_ext: np.ndarray) -> np.ndarray:  # fmt: skip
                return helped(qq, vv, f_ext, f_lambda)

            fused = fused_total_force(self, travel_args(self.planner, self.consensus.estimate,
                                                        self.params, self._held),
                                      travel_gains(self.params),
                                      adjust if len(helpers) else None)  # fmt: skip
        try:
            q_new, v_new, ev, stats = integrate(
                q, v, ctx.dt_s, self._evaluate, self._force, external, self.integ,
                self.conn.lambda2_min, self._current, box=self.world.bounds_m,
                box_margin_m=self.conn.ro_m, total_force=fused,
            )  # fmt: skip
        finally:
            self._held = None
        self._current = ev
        self._stats["substeps"] += stats.substeps
        self._stats["rejections"] += stats.rejections
        self._stats["stalls"] += int(stats.stalled)
        graph, lam, nu = ev[1]
        self._observe(q_new, graph, lam, nu)
        self._bookkeep(q, q_new, float(lam), (ctx.step + 1) * ctx.dt_s, ctx.dt_s)
        return TeamState(q_new, v_new)

    def _bookkeep(self, q: np.ndarray, q_new: np.ndarray, lam: float, t_s: float, dt: float):
        pl = self.planner
        if jit.enabled():  # the same sums and maximum, compiled
            far = _kernels().travel_stretch_kernel(
                self._travelled, np.ascontiguousarray(q), np.ascontiguousarray(q_new), pl.explorer
            )
            if far >= 0.0:
                self._stretch = max(self._stretch, far)
        else:
            self._travelled += np.linalg.norm(q_new - q, axis=1)
            ex = np.flatnonzero(pl.explorer)
            if len(ex) > 1:
                d = np.linalg.norm(q_new[ex, None] - q_new[None, ex], axis=-1)
                self._stretch = max(self._stretch, float(d.max()))
        if np.isfinite(lam):
            self._lambda_sum += lam
            self._lambda_count += 1
        self._max_primes = max(self._max_primes, int((pl.role == PRIME).sum()))
        if self.params.reference_filter:
            if self.filter is None:
                self.filter = ReferenceFilter(q, dt)
            dev = np.linalg.norm(self.filter.update(q_new) - q_new, axis=1)
            self._filter_dev = max(self._filter_dev, float(dev.max()))
        self._t_s = t_s
        if self._completion is None and pl.done():
            self._completion = t_s

    def add_target(self, robot: int, position_m: Any, stay_s: float = 3.0, **kw: Any) -> None:
        """Give ``robot`` one more target while the team runs (Python API)."""
        self._record_target(robot, self.targets.add(robot, position_m, stay_s, **kw))
        self._completion = None

    def _record_target(self, robot: int, z: Any) -> None:
        """A ``target_added`` event (:mod:`tether.targets_recorded`) for target ``z``."""
        self.emit("target_added", robot, target=z.id, position_m=[float(v) for v in z.position_m],
                  stay_s=z.stay_s, appear_s=z.appear_s)  # fmt: skip

    def done(self) -> bool:
        return self._completion is not None

    # -- results ---------------------------------------------------------------------
    def step_values(self) -> dict[str, Any]:
        role = self.planner.role
        primes = np.flatnonzero(role == PRIME)
        count = np.bincount(role, minlength=len(ROLE_NAMES))
        return {
            "lambda2_weighted": float(self._current[0]) if self._current else float("nan"),
            "prime": int(primes[0]) if len(primes) else -1,
            "n_travelers": int(count[PRIME] + count[SECONDARY]),
            "n_anchors": int(count[ANCHOR]),
            "prime_efficiency": self._prime_eff,
        }

    def robot_values(self) -> dict[str, np.ndarray]:
        out = {"role": _ROLE_ARRAY[self.planner.role]}
        if self.filter is not None:  # the reference of eq. (16), from step 1 on
            for d, axis in zip(range(self.filter.position.shape[1]), "xyz", strict=False):
                out[f"{axis}_ref_m"] = self.filter.position[:, d].copy()
        return out

    def metrics(self) -> dict[str, Any]:
        pl = self.planner
        ex = pl.explorer
        out = {
            **super().metrics(),
            **pl.summary(),
            "completion_time_s": self._completion,
            "explorers": int(ex.sum()),
            "mean_explorer_distance_m": float(self._travelled[ex].mean()) if ex.any() else 0.0,
            "max_explorer_stretch_m": self._stretch,
            "mean_lambda2_weighted": self._lambda_sum / max(self._lambda_count, 1),
            "elections": self._elections,
            "max_simultaneous_primes": self._max_primes,
            "help_requests": self._help_requests,
            "helper_robot_s": self._helper_s,
        }
        if self.filter is not None:
            out["reference_filter_max_deviation_m"] = self._filter_dev
        return out
