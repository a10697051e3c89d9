"""The BS planner: asynchronous replanning under recurrent connectivity.

Recurrent-connectivity paper (Banfi et al., Sec. III-VI). Every step the BS
updates readiness (Sec. VI); as soon as at least ``theta`` robots are ready it
plans for them:

1. builds ``G^t`` from its known map (:mod:`tether.recurrent.expgraph`);
2. utilities of frontiers, eq. (1): ``U(f) = g(f) / min_{j in R^t} d(p_j, f)^2``;
3. the optimal configuration (Sec. IV, ``method="apx"`` Algorithm 1 or
   ``"ilp"``) with the non-ready robots' goals as fixed relays;
4. the deployment (Sec. V): Hungarian assignment of the ready and the
   connected non-ready robots, surplus robots to "fake" frontiers;
5. the relay paths ``P_f`` bind robots until ``f``'s data reaches the BS
   (Sec. VI). ``relay_binding="frontiers"`` is the paper's rule: ``P_f`` for
   every frontier and fake frontier of the plan. ``"assigned"`` (the default,
   a deviation chosen by measurement, see ``docs/explanation/recurrent.md``) also binds
   a ``P_f`` for every other robot the plan sends to a new goal (relays and
   re-assigned busy robots), so a relay is held until the chain that links
   its own goal to the BS has formed.

Recovery (Sec. VII-B): a robot that cannot reach its goal aborts; all robots
of the branches it belongs to (those bound with it by some ``P_f``) are
preempted, stop where they are and become ready for a new plan. A robot that
fails (``sim.alive``; the BS is told at once) is treated the same way and
leaves the team: its goal is no longer kept in configurations, and ``theta``
counts only live robots. Preempted robots that the failure cut off from the
BS cannot be reached by a plan; they head back towards the BS on their own
map until they link to it again, stop there and become ready (an addition:
the paper's recovery assumes the BS can reach the preempted robots).

A failed attempt (no frontier reachable within the budget) is retried when
the ready set changes, or after ``retry_steps`` steps if the BS map grew.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tether.graph import components
from tether.paths.geodesic import Geodesics
from tether.recurrent.exploration.sim import ExplorationSim, GoalKind
from tether.recurrent.planning.configuration import check_configuration, optimal_configuration
from tether.recurrent.planning.deployment import optimal_deployment
from tether.recurrent.planning.expgraph import FRONTIER, ExplorationGraph, GraphBuilder
from tether.recurrent.planning.readiness import (
    BINDINGS,
    ReadinessTracker,
    binding_targets,
    relay_paths,
)
from tether.sensing.links import link_pairs

__all__ = ["RecurrentStrategy", "frontier_utilities"]


def frontier_utilities(
    graph: ExplorationGraph, dist: np.ndarray, exclude: set[int] = frozenset()
) -> dict[int, float]:
    """Eq. (1): ``U(f) = g(f) / min_j d(p_j, f)^2`` for reachable frontiers.

    ``dist`` is ``(k, V)``: geodesic distances from the ready robots' positions
    to the vertices. Distances below one cell count as one cell.
    """
    out: dict[int, float] = {}
    if dist.shape[0] == 0:
        return out
    dmin = dist.min(axis=0)
    for f in graph.frontiers.tolist():
        if f in exclude or not np.isfinite(dmin[f]) or graph.gain[f] <= 0:
            continue
        out[f] = float(graph.gain[f] / max(dmin[f], 1.0) ** 2)
    return out


@dataclass
class RecurrentStrategy:
    """The paper's centralized asynchronous strategy (``theta``, APX/ILP, ``delta``).

    Parameters
    ----------
    theta
        Replan when at least ``theta`` robots are ready (capped at the team size).
    method, delta, backend
        Configuration solver (see :func:`optimal_configuration`).
    count_planning_time
        If true, newly assigned robots wait ``ceil(planning time / 1 s)`` steps
        (the paper's Fig. 4a); otherwise planning is instantaneous (Fig. 4b).
    check
        Run :func:`check_configuration` on every plan and record violations.
    retry_steps
        Minimum steps between two failed attempts with the same ready set.
    time_limit_s
        Time budget of one plan with ``method="ilp"``: the exact solver returns
        the best configuration found within it (``proven_optimal`` false, APX
        as fallback; see :func:`optimal_configuration`).
    relay_binding
        ``"assigned"`` or ``"frontiers"`` (the paper's Sec. VI rule), see above.
    """

    theta: int = 1
    method: str = "apx"
    delta: int = 4
    backend: str = "highs"
    count_planning_time: bool = False
    check: bool = False
    retry_steps: int = 10
    time_limit_s: float | None = 10.0
    relay_binding: str = "assigned"
    name: str = "recurrent"
    plans: list[dict[str, Any]] = field(default_factory=list)
    violations: list[str] = field(default_factory=list)

    # ------------------------------------------------------------------ protocol
    def start(self, sim: ExplorationSim) -> None:
        cfg = sim.cfg
        self.builder = GraphBuilder(
            sim.occupied,
            sim.link,
            cfg.coarse_factor,
            int(round(cfg.sensor_range_cells)),
            cfg.min_cluster_cells,
            cfg.max_cluster_extent,
        )
        self.tracker = ReadinessTracker()
        self.visited: dict[int, np.ndarray] = {}  # coarse cell key -> position
        self._last_attempt: tuple[frozenset[int], int, int] | None = None
        self.finished = False
        self.blocked = np.zeros(sim.n, dtype=bool)
        self.failed_seen = np.zeros(sim.n, dtype=bool)
        self._was_connected = sim.connected.copy()
        self.recoveries: list[dict[str, Any]] = []
        if self.relay_binding not in BINDINGS:
            raise ValueError(f"relay_binding must be one of {BINDINGS}")

    def metrics(self) -> dict[str, Any]:
        issued = [p for p in self.plans if p["issued"]]
        times = [p["planning_time_s"] for p in issued]
        return {
            "plans": len(issued),
            "plan_attempts": len(self.plans),
            "planning_time_mean_s": float(np.mean(times)) if times else 0.0,
            "planning_time_max_s": float(np.max(times)) if times else 0.0,
            "planning_time_total_s": float(np.sum(times)) if times else 0.0,
            "constraint_violations": len(self.violations),
            "exploration_finished": self.finished,
            "plans_not_proven_optimal": sum(not p.get("proven_optimal", True) for p in issued),
            "plans_timed_out": sum(bool(p.get("timed_out", False)) for p in issued),
            "plans_apx_delta_capped": sum(bool(p.get("apx_delta_capped")) for p in issued),
            "plans_after_failures": sum(p["step"] >= self._first_failure for p in issued),
            "robots_preempted_by_failures": sum(len(x["preempted"]) for x in self.recoveries),
        }

    @property
    def _first_failure(self) -> float:
        return min((x["step"] for x in self.recoveries), default=float("inf"))

    def relaying(self, sim: ExplorationSim) -> np.ndarray:
        """Robots standing at their goal on an open ``P_f`` of another robot's goal."""
        keys = self.goal_keys(sim)
        held: set[int] = set()
        for o in self.tracker.obligations:
            held |= o.members - {o.target}
        on = np.array([int(k) in held for k in keys.tolist()], dtype=bool)
        return on & sim.at_goal & ~sim.moved & sim.alive

    def goal_keys(self, sim: ExplorationSim) -> np.ndarray:
        """Coarse node of every robot's goal (location keys for readiness)."""
        return self._key(sim, sim.goal)

    @staticmethod
    def _key(sim: ExplorationSim, points: np.ndarray) -> np.ndarray:
        f = sim.cfg.coarse_factor
        c = np.floor(np.asarray(points, dtype=float) / f).astype(np.intp)
        return c[..., 0] * (sim.shape[1] // f + 1) + c[..., 1]

    def update(self, sim: ExplorationSim) -> None:
        self._update(sim)
        self._was_connected = sim.connected.copy()

    def _update(self, sim: ExplorationSim) -> None:
        for r in np.flatnonzero(self.blocked):
            self.abort(sim, int(r))
        self.blocked[:] = False
        for r in np.flatnonzero(~sim.alive & ~self.failed_seen):
            self.failed_seen[r] = True
            self.recover(sim, int(r))
        # robots cut off by a failure that found the BS's network again stop there
        for r in np.flatnonzero((sim.goal_kind == GoalKind.HOME) & sim.connected):
            sim.stop(int(r))
        keys = self.goal_keys(sim)
        self.tracker.update(keys, sim.at_goal, sim.delivered)
        done = sim.at_goal & sim.scanned & sim.alive
        ready = self.tracker.ready(done, sim.connected, keys)
        n_ready = int(ready.sum())
        if n_ready < min(self.theta, int(sim.alive.sum())) or n_ready == 0:
            return
        ready_set = frozenset(np.flatnonzero(ready).tolist())
        version = sim.knowledge.global_version
        last = self._last_attempt
        same = last is not None and last[0] == ready_set
        if same and (last[1] == version or sim.t - last[2] < self.retry_steps):
            return
        self._last_attempt = (ready_set, version, sim.t)
        self.plan(sim, ready)

    # ------------------------------------------------------------------ recovery
    def abort(self, sim: ExplorationSim, robot: int) -> None:
        """Recovery rule: ``robot`` cannot reach its goal; preempt its branches."""
        keys = self.goal_keys(sim)
        branch = sorted(self.tracker.branch(robot, keys))
        self.tracker.drop({int(keys[r]) for r in branch})
        for r in branch:
            sim.stop(r)
        sim.log("abort", robot=robot, preempted=branch)

    def recover(self, sim: ExplorationSim, robot: int) -> None:
        """``robot`` failed: preempt its branches (Sec. VII-B); cut-off robots head home.

        The branches are those of the failed robot, of every robot standing at its
        goal that lost its link to the BS with the failure, and of every robot whose
        goal no longer links to the BS through the goals of the live robots (the
        configurations treat non-ready goals as linked, Sec. IV-A, which the failed
        robot's goal may have been needed for; ``C^t`` on the BS's known map).
        """
        keys = self.goal_keys(sim)
        keys[robot] = self._key(sim, sim.goal_at_failure[robot])  # where it was bound
        lost = self._was_connected & ~sim.connected & sim.alive & sim.at_goal
        branch_set = self.tracker.branch(robot, keys)
        for r in np.flatnonzero(lost | self._orphans(sim)):
            branch_set |= self.tracker.branch(int(r), keys)
        branch = sorted(r for r in branch_set if r != robot)
        self.tracker.drop({int(keys[r]) for r in [robot, *branch]})
        homing = []
        for r in branch:
            if not sim.alive[r]:
                continue
            sim.stop(r)
            if not sim.connected[r] and self._head_home(sim, r):
                homing.append(r)
        self.recoveries.append({"step": sim.t, "robot": robot, "preempted": branch})
        sim.log("recovery", robot=robot, preempted=branch, homing=homing)

    @staticmethod
    def _orphans(sim: ExplorationSim) -> np.ndarray:
        """Live robots whose goal does not link to the BS through live robots' goals."""
        live = np.flatnonzero(sim.alive)
        points = np.vstack([sim.base[None], sim.goal[live]])
        free = sim.knowledge.global_known & ~sim.occupied
        _, lab = components(len(points), link_pairs(sim.link, free, points))
        out = np.zeros(sim.n, dtype=bool)
        out[live] = lab[1:] != lab[0]
        return out

    @staticmethod
    def _head_home(sim: ExplorationSim, r: int) -> bool:
        """Send ``r`` towards the BS on its own map (False if it knows no way)."""
        coarse = sim.coarse_known(sim.knowledge.local_known[r])
        src = int(coarse.node_at(sim.pos[r])[0])
        dst = int(coarse.node_at(sim.base)[0])
        if src < 0 or dst < 0:
            return False
        _, pred = coarse.distances([src], predecessors=True)
        if src != dst and pred[0, dst] < 0:
            return False
        path = np.vstack([sim.pos[r : r + 1], coarse.path(pred[0], dst)])
        sim.assign(r, sim.base, GoalKind.HOME, path)
        return True

    # ------------------------------------------------------------------ planning
    def plan(self, sim: ExplorationSim, ready: np.ndarray) -> None:
        tic = time.perf_counter()
        coarse = sim.coarse_known()
        keys = self.goal_keys(sim)
        for r in np.flatnonzero(sim.alive):  # robots stand on (or head to) vertices
            self.visited.setdefault(int(keys[r]), sim.goal[r].copy())
        relays = np.array(list(self.visited.values())).reshape(-1, 2)
        graph = self.builder.build(sim.knowledge.global_known, sim.base, relays, coarse)
        goal_v = graph.vertices_of_nodes(coarse.node_at(sim.goal))
        ready_ids = np.flatnonzero(ready)
        nonready = np.flatnonzero(~ready & sim.alive)
        fixed = {int(goal_v[r]) for r in nonready if goal_v[r] > 0}
        movable = np.flatnonzero(ready | sim.connected)  # constraint (IV)
        dist, geo = self._distances(graph, sim.pos[movable])
        row = {int(r): k for k, r in enumerate(movable)}
        ready_rows = [row[int(r)] for r in ready_ids]
        utilities = frontier_utilities(graph, dist[ready_rows], exclude=fixed)
        record: dict[str, Any] = {
            "step": sim.t,
            "n_ready": len(ready_ids),
            "n_vertices": graph.n,
            "n_edges": len(graph.edges),
            "n_frontiers": len(utilities),
            "issued": False,
        }
        if not utilities:
            if len(ready_ids) == sim.alive.sum() and len(graph.frontiers) == 0:
                self.finished = True
            record.update(planning_time_s=time.perf_counter() - tic, utility=0.0, size=0)
            self.plans.append(record)
            sim.log("plan", **record)
            return
        nxg = graph.to_networkx()
        conf = optimal_configuration(
            nxg,
            0,
            utilities,
            len(ready_ids),
            method=self.method,
            delta=self.delta,
            fixed=fixed,
            backend=self.backend,
            time_limit_s=self.time_limit_s,
        )
        if not conf.vertices & set(utilities):
            record.update(planning_time_s=time.perf_counter() - tic, utility=0.0, size=0)
            self.plans.append(record)
            sim.log("plan", **record)
            return
        assignment, fake = self._deploy(
            sim, graph, nxg, conf, ready_ids, movable, goal_v, dist, row
        )
        planning_time = time.perf_counter() - tic
        if self.check:
            # the BS vertex is always part of the network: robots waiting there need no goal
            alive = np.flatnonzero(sim.alive)
            previous = {int(r): int(goal_v[r]) for r in alive if goal_v[r] != 0}
            problems = check_configuration(
                nxg,
                0,
                conf.vertices,
                utilities.keys(),
                len(ready_ids),
                fixed=fixed,
                assignment={r: v for r, v in assignment.items() if v != 0},
                previous_goals=previous,
                ready=ready_ids.tolist(),
                connected=[int(r) for r in movable if not ready[r]],
            )
            self.violations.extend(f"step {sim.t}: {p}" for p in problems)
        delay = math.ceil(planning_time) if self.count_planning_time else 0
        for r, v in assignment.items():
            if goal_v[r] == v and not ready[r]:
                continue  # non-ready robot keeps its goal
            kind = (
                GoalKind.FAKE
                if v in fake
                else GoalKind.FRONTIER
                if graph.kind[v] == FRONTIER
                else GoalKind.RELAY
            )
            k = row[r]
            path = geo.path(k, int(graph.nodes[v]))
            path = np.vstack([sim.pos[r : r + 1], path])
            sim.assign(r, graph.positions[v], kind, path, delay=delay)
        self._bind(sim, graph, assignment, fake, coarse)
        record.update(
            issued=True,
            planning_time_s=planning_time,
            solver_time_s=conf.solve_time_s,
            utility=conf.utility,
            size=len(conf.vertices),
            n_fake=len(fake),
            n_assigned=len(assignment),
            method=conf.method,
            proven_optimal=conf.proven_optimal,
            timed_out=conf.timed_out,
            fallback=conf.fallback,
        )
        if conf.apx_delta_capped:  # MAX_TABLE_SUBSETS lowered delta for this plan
            record.update(apx_delta=conf.apx_delta, apx_delta_capped=True)
        self.plans.append(record)
        sim.log("plan", **record)

    @staticmethod
    def _distances(graph: ExplorationGraph, points: np.ndarray) -> tuple[np.ndarray, Geodesics]:
        """Distances from each point to every vertex ``(k, V)``, and the paths to anywhere."""
        src = graph.coarse.node_at(points)
        if (src < 0).any():
            raise RuntimeError("a robot stands outside the known traversable space")
        geo = graph.coarse.geodesics(src, lazy=True)
        return geo.dist[:, graph.nodes], geo

    def _deploy(
        self,
        sim: ExplorationSim,
        graph: ExplorationGraph,
        nxg: Any,
        conf: Any,
        ready_ids: np.ndarray,
        movable: np.ndarray,
        goal_v: np.ndarray,
        dist: np.ndarray,
        row: dict[int, int],
    ) -> tuple[dict[int, int], set[int]]:
        """Sec. V deployment (:func:`tether.recurrent.deployment.optimal_deployment`)."""
        ready_set = {int(r) for r in ready_ids}
        busy = {int(r): int(goal_v[r]) for r in movable if int(r) not in ready_set}

        def travel(r: int, v: int) -> float:
            return float(dist[row[int(r)], v])

        out = optimal_deployment(
            nxg,
            0,
            conf.vertices,
            sorted(ready_set),
            travel,
            connected_busy=busy,
            fixed=conf.fixed,
        )
        return {int(r): int(v) for r, v in out.assignment.items()}, set(out.fake_frontiers)

    def _bind(
        self,
        sim: ExplorationSim,
        graph: ExplorationGraph,
        assignment: dict[int, int],
        fake: set[int],
        coarse: Any,
    ) -> None:
        """Relay paths ``P_f`` of the plan (Sec. VI; whose: ``relay_binding``)."""
        goals: dict[int, int] = {}
        times: dict[int, float] = {}
        goal_v = graph.vertices_of_nodes(coarse.node_at(sim.goal)).tolist()
        for r in np.flatnonzero(sim.alive).tolist():
            v = goal_v[r]
            if v < 0 or v in goals.values():
                continue
            goals[r] = v
            scan = sim.cfg.scan_steps if sim.goal_kind[r] == GoalKind.FRONTIER else 0
            # robots assigned by this plan move from the next step on, like the
            # ones already under way: no extra step (it reordered P_f, see
            # docs/explanation/recurrent.md)
            wait = sim.hold_steps(r)
            times[r] = wait + sim.remaining_distance(r) / sim.cfg.speed_cells + scan
        frontier_like = {v for v in assignment.values() if graph.kind[v] == FRONTIER} | fake
        targets = binding_targets(assignment, frontier_like, self.relay_binding)
        targets = [r for r in targets if r in goals]
        paths = relay_paths(goals, times, targets, graph.edges, base=0)
        keys = self.goal_keys(sim)
        for f, members in paths.items():
            if members is None:
                continue
            self.tracker.add(int(keys[f]), [int(keys[m]) for m in members], plan=len(self.plans))
