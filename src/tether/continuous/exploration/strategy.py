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
from tether.continuous.connectivity.dynamics import displacement_step
from tether.continuous.connectivity.external import check_failures
from tether.continuous.connectivity.placement import safe_team
from tether.continuous.connectivity.strategy import ConnectivityStrategy
from tether.continuous.exploration.checks import check_planning_grid, target_book
from tether.continuous.exploration.consensus import EfficiencyConsensus
from tether.continuous.exploration.election import Election
from tether.continuous.exploration.motion import (
    anchor_targets,
    travel_args,
    travel_gains,
    traveling_forces,
)
from tether.continuous.exploration.params import MultiTargetParams
from tether.continuous.exploration.recruit import HelpFlood, RequestDepth, help_rows
from tether.continuous.exploration.reference_filter import ReferenceFilter
from tether.continuous.exploration.roles import (
    ANCHOR,
    CONNECTOR,
    PRIME,
    ROLE_NAMES,
    SECONDARY,
    RolePlanner,
)
from tether.continuous.exploration.substep import fused_total_force
from tether.continuous.exploration.targets import TargetBook, outside_heights
from tether.continuous.exploration.travel import efficiency
from tether.errors import ScenarioError
from tether.registry import STRATEGIES
from tether.sim import StepContext, TeamState
from tether.world.world import World


@cache
def _kernels() -> SimpleNamespace:
    """:mod:`tether.continuous.exploration.step_kernels`, imported on first use (it loads
    numba; an import statement per call costs microseconds)."""
    from tether.continuous.exploration import step_kernels

    return SimpleNamespace(
        any_row_beyond=step_kernels.any_row_beyond,
        travel_stretch_kernel=step_kernels.travel_stretch_kernel,
    )


def _anchor_leaves(q: np.ndarray, held: np.ndarray, targets: np.ndarray, rz_m: float) -> bool:
    """True if an anchored robot ``held[k]`` is ``Rz`` or farther from ``targets[k]``.

    ``q`` is ``(n, dim)``, ``targets`` ``(len(held), dim)``. With the kernels, one
    compiled call (:func:`tether.continuous.exploration.step_kernels.any_row_beyond`, the same
    distances as ``numpy.linalg.norm``); the numpy test otherwise (the reference).
    """
    if jit.enabled():
        return bool(_kernels().any_row_beyond(q, held, targets, rz_m))
    return bool(np.any(np.linalg.norm(q[held] - targets, axis=1) >= rz_m))


_ROLE_ARRAY = np.array(ROLE_NAMES)  # role names by role code


@STRATEGIES.register("multi_target")
class MultiTargetStrategy(ConnectivityStrategy):
    """Decentralized multi-target exploration (Algorithms 1-2) on the connectivity force."""

    name = "multi_target"
    Params = MultiTargetParams
    force_with_weights = False  # the fused sub-step (exploration/substep.py) makes the force

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
        check_failures(params.estimator.failures, initial.n, scenario.source)
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
        self._reference_m = state.positions.copy()  # the filter's start: the robots
        self._t_s = 0.0
        self._completion: float | None = 0.0 if self.planner.done() else None
        self._travelled = np.zeros(n)
        self._stretch = 0.0
        self._lambda_sum, self._lambda_count = 0.0, 0
        self._max_primes = 0
        self._elections = 0
        self._filter_dev = 0.0
        self._filter_peak = np.zeros(2)  # the reference's largest speed and acceleration
        self._prime_eff = float("nan")
        self._anyone = np.ones(n, dtype=bool)
        self._vacant_steps = 0
        self._had_prime = False
        self._vacancy_run = 0
        self._longest_vacancy = 0
        self._held: tuple[np.ndarray, np.ndarray] | None = None
        self._last_links: np.ndarray | None = None
        self._external = self._fused = None
        self._anchor_outside_steps = 0
        self._current = self.evaluate(state.positions)

    def _anchors(self) -> tuple[np.ndarray, np.ndarray]:
        """The anchored robots and their targets (fixed while a period is integrated)."""
        if self._held is not None:
            return self._held
        held = np.flatnonzero(self.planner.anchored())
        return held, anchor_targets(self.planner, held, self.world.dim)

    def evaluate(self, q: np.ndarray) -> tuple[float, Any]:
        lam, cache = super().evaluate(q)
        if self.params.guard == "enforce":  # the anchor's ball is part of what it enforces
            held, targets = self._anchors()
            if len(held) and _anchor_leaves(q, held, targets, self.params.rz_m):
                return -np.inf, cache
        return lam, cache

    def forces(self, q: np.ndarray, v: np.ndarray, cache: Any) -> tuple:
        """``(f_lambda + f_i, f_lambda, displacement step)``: Algorithm 2's ``f_i`` this
        period (:func:`traveling_forces`, helpers), in one compiled call when it can."""
        if self._fused is not None:
            return self._fused(q, v, cache)
        f_lambda = self.connectivity_force(cache)
        f_i = self._external(q, v, f_lambda)
        if self.estimator is not None:  # a failed robot exerts no force, as in connectivity
            f_i = f_i * self.estimator.comm.alive()[:, None]
        total = f_lambda + f_i
        return total, f_lambda, displacement_step(v, total, self.integ.mass_kg,
                                                  self.integ.max_step_m)  # fmt: skip

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
        """Algorithm 1, then this period's message rounds: election, eq. (13), help.

        The winner of an election always takes the prime role, even if it reached its
        target (or finished anchoring) while the result travelled to it: it then holds the
        role at its target and at once hosts the next election (as a prime that reaches
        its target does, line 14 of Algorithm 1). So no prime exists only while a result
        floods from host to winner, at most ``N - 1`` rounds (Sec. 3.3); a winner that
        declined would leave the team without a prime for a whole new election.

        ``Lambda_p`` (eq. (12)) measures how a traveling prime tracks its path. While no
        prime travels (no prime, or one holding at its target during its election) it is
        not defined, and nobody pins the consensus of eq. (13): the estimates keep
        averaging among neighbours what they last knew.
        """
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
        anyone = self._anyone  # a winner always takes the role (see _communicate's docstring)
        for _ in range(rounds):
            out = self.election.round(links, pl.role == SECONDARY, crit, anyone, wants)
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
        self._prime_eff = float("nan")  # no prime travels: Lambda_p is not defined
        where = np.flatnonzero(robots == prime)
        if len(where):  # eqs. (11)-(12)
            k = int(where[0])
            err = (1 - p.alpha_lambda) * floats.norm(states.velocity_mps[k] - v[prime]) \
                + p.alpha_lambda * states.distance_m[k]  # fmt: skip
            band = (p.xc_frac * p.v_cruise_mps, p.xm_frac * p.v_cruise_mps)
            self._prime_eff = float(efficiency(np.array([err]), *band)[0])
        pin = prime if len(where) else -1  # only a traveling prime feeds eq. (13)
        for _ in range(rounds):
            self.consensus.round(links, dt_s / rounds, pin, self._prime_eff)
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
        held = self._held = self._anchors()  # roles and targets stay until the next period

        p, helpers = self.params, self._helpers
        parents_m = self.help.parent_m[helpers]

        def helped(qq: np.ndarray, vv: np.ndarray, f: np.ndarray, f_lambda: np.ndarray
                   ) -> np.ndarray:  # fmt: skip
            """Recruited robots follow their parent instead (:func:`help_rows`)."""
            return help_rows(qq, vv, f, f_lambda, helpers, parents_m, keep_m=p.rs_inner_m,
                             kp=p.kp_n_per_m, kv=p.kv_ns_per_m,
                             max_force_n=p.max_travel_force_n,
                             lambda_factor=p.help_lambda_factor)  # fmt: skip

        def external(qq: np.ndarray, vv: np.ndarray, f_lambda: np.ndarray) -> np.ndarray:
            f = traveling_forces(qq, vv, f_lambda, self.planner, self.consensus.estimate, p,
                                 anchors=self._held)  # fmt: skip
            return helped(qq, vv, f, f_lambda) if len(helpers) else f

        self._external, self._fused = external, None
        if jit.enabled() and self.estimator is None:  # one compiled call per sub-step

            def adjust(qq: np.ndarray, vv: np.ndarray, f_lambda: np.ndarray,
                       f_ext: np.ndarray) -> np.ndarray:  # fmt: skip
                return helped(qq, vv, f_ext, f_lambda)

            self._fused = fused_total_force(self, travel_args(self.planner,
                                                              self.consensus.estimate,
                                                              self.params, self._held),
                                            travel_gains(self.params),
                                            adjust if len(helpers) else None)  # fmt: skip
        try:
            q_new, v_new, ev, stats = self.integrate(q, v, ctx.dt_s, self)
        finally:
            self._held = None
            self._external = self._fused = None
        graph, lam, nu = ev[1]
        self._observe(q_new, graph, lam, nu)
        self._bookkeep(q, q_new, float(lam), (ctx.step + 1) * ctx.dt_s, ctx.dt_s, held)
        return TeamState(q_new, v_new)

    def _bookkeep(
        self,
        q: np.ndarray,
        q_new: np.ndarray,
        lam: float,
        t_s: float,
        dt: float,
        anchors: tuple[np.ndarray, np.ndarray],
    ) -> None:
        """This period's sums, extremes and counts; ``anchors``: the held robots and their
        targets (:meth:`_anchors`, unchanged since the period began)."""
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
        # the start-up election runs before any prime exists (Sec. 3.2): not a vacancy
        has_prime = bool((pl.role == PRIME).any())
        self._had_prime = self._had_prime or has_prime
        vacant = self._had_prime and not has_prime and bool((pl.role == SECONDARY).any())
        self._vacant_steps += vacant
        self._vacancy_run = self._vacancy_run + 1 if vacant else 0
        self._longest_vacancy = max(self._longest_vacancy, self._vacancy_run)
        held, targets = anchors
        if len(held) and _anchor_leaves(q_new, held, targets, self.params.rz_m):
            self._anchor_outside_steps += 1
        if self.params.reference_filter:
            if self.filter is None:
                self.filter = ReferenceFilter(q, dt)
            dev, speed, accel = self.filter.advance(q_new)
            self._filter_dev = max(self._filter_dev, dev)
            self._filter_peak = np.maximum(self._filter_peak, [speed, accel])
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
            **super().step_values(),
            "lambda2_weighted": float(self._current[0]) if self._current else float("nan"),
            "prime": int(primes[0]) if len(primes) else -1,
            "n_travelers": int(count[PRIME] + count[SECONDARY]),
            "n_anchors": int(count[ANCHOR]),
            "prime_efficiency": self._prime_eff,
        }

    def robot_values(self) -> dict[str, np.ndarray]:
        out = {"role": _ROLE_ARRAY[self.planner.role]}
        if self.params.reference_filter:  # the reference of eq. (16), from step 0 on (the
            # recorder keeps the columns of the first record only)
            ref = self.filter.position if self.filter is not None else self._reference_m
            for d, axis in zip(range(ref.shape[1]), "xyz", strict=False):
                out[f"{axis}_ref_m"] = ref[:, d].copy()
        return out

    def metrics(self) -> dict[str, Any]:
        pl = self.planner
        ex = pl.explorer
        summary = pl.summary()
        out = {
            **super().metrics(),
            **summary,
            # the mission's completion: none while a target is pending or once one is dropped
            "completion_time_s": self._completion if summary["targets_dropped"] == 0 else None,
            "explorers": int(ex.sum()),
            "mean_explorer_distance_m": float(self._travelled[ex].mean()) if ex.any() else 0.0,
            "max_explorer_stretch_m": self._stretch,
            "mean_lambda2_weighted": self._lambda_sum / max(self._lambda_count, 1),
            "elections": self._elections,
            "max_simultaneous_primes": self._max_primes,
            "prime_vacant_steps": self._vacant_steps,
            "longest_prime_vacancy_steps": self._longest_vacancy,
            "anchor_outside_steps": self._anchor_outside_steps,
            "help_requests": self._help_requests,
            "helper_robot_s": self._helper_s,
        }
        if self.filter is not None:
            out["reference_filter_max_deviation_m"] = self._filter_dev
            out["reference_filter_max_speed_mps"] = float(self._filter_peak[0])
            out["reference_filter_max_accel_mps2"] = float(self._filter_peak[1])
        return out
