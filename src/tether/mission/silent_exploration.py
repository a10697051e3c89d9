"""The no-communication paradigm: a frontier-driven leader, followers on the steering law.

Kerestecioglu & Cezayirli's team (:mod:`tether.silent`) on the exploration mission:
robots exchange no messages. One robot, the leader, explores: it heads for the
frontier of best utility (``g(f) / d^2``, as every explorer of the mission) on the
map *it sensed itself*; when it has no frontier left it heads back to the base
station. Every robot, the leader included, then takes the Local Steering Strategy's
step (:func:`tether.silent.steering.team_steps`, cost (13)): the relative positions
of the robots it senses (those it has a link to: within ``d_max`` = the link range,
in line of sight) are all it uses, and constraints (1)-(2) keep every such pair
within ``d_max`` in free space. A step that would cross a wall is halved until it
does not (walls are not in the paper; a wall between two robots can still cut their
link, and the mission counts it).

The mission's data layer is the same for every paradigm: robots whose links connect
them share their maps, and a group linked to the base station delivers what it holds.
The leader plans on its own sensing only, so no robot's decision uses what another
robot told it.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from pydantic import Field

from tether.config import MAX_LENGTH_M
from tether.errors import ScenarioError
from tether.recurrent.exploration.sim import ExplorationSim, GoalKind
from tether.recurrent.planning.expgraph import frontier_nodes, window_counts
from tether.recurrent.strategy import ExplorationParams, ExplorationPlugin
from tether.registry import STRATEGIES
from tether.silent.steering import team_steps
from tether.sim import TeamState
from tether.world.los import segment_free
from tether.world.world import World

__all__ = ["LeaderFollowerPolicy", "SilentExploration", "SilentExplorationParams"]


@dataclass
class LeaderFollowerPolicy:
    """A frontier-driven leader and followers under the Local Steering Strategy (cells)."""

    d_max_cells: float
    d0_cells: float
    gamma: float = 0.2
    min_separation_cells: float = 10.0
    leader: int = 0
    stuck_steps: int = 20
    name: str = "silent_exploration"
    frontiers_chosen: int = 0
    blocked_steps: int = 0
    returned: bool = False
    _banned: set[tuple[int, int]] = field(default_factory=set)

    def start(self, sim: ExplorationSim) -> None:
        self.leader %= sim.n
        self.own = np.zeros(sim.shape, dtype=bool)
        self.path = sim.pos[self.leader : self.leader + 1].copy()
        self.goal_kind = GoalKind.NONE
        self._since_progress = 0
        self._best_left = np.inf
        self._absorb(sim)
        self._plan(sim)
        self._steer(sim)

    def metrics(self) -> dict[str, Any]:
        return {
            "leader": self.leader,
            "frontiers_chosen": self.frontiers_chosen,
            "leader_blocked_steps": self.blocked_steps,
            "leader_returned": self.returned,
        }

    def update(self, sim: ExplorationSim) -> None:
        self._absorb(sim)
        left = self._left(sim)
        if left < self._best_left - 0.5:
            self._best_left, self._since_progress = left, 0
        else:
            self._since_progress += 1
        arrived = left < 0.5
        stale = (
            self.goal_kind == GoalKind.FRONTIER
            and sim.t % 5 == 0
            and window_counts(~self.own, self.path[-1:], 1)[0] == 0
        )
        stuck = self._since_progress >= self.stuck_steps
        if stuck and self.goal_kind == GoalKind.FRONTIER:
            self._banned.add(tuple(np.floor(self.path[-1]).astype(int).tolist()))
        if (arrived and sim.scanned[self.leader]) or stale or stuck:
            self._plan(sim)
        self._steer(sim)

    # -- the leader's own map and plan -------------------------------------------------
    def _absorb(self, sim: ExplorationSim) -> None:
        flat = self.own.reshape(-1)
        for r, cells in sim.sensed:
            if r == self.leader:
                flat[cells] = True

    def _left(self, sim: ExplorationSim) -> float:
        return float(np.linalg.norm(self.path[-1] - sim.pos[self.leader]))

    def _plan(self, sim: ExplorationSim) -> None:
        """Best frontier of the leader's own map, else home; ``self.path`` in cells."""
        self._since_progress, self._best_left = 0, np.inf
        pos = sim.pos[self.leader]
        coarse = sim.coarse_known(self.own)
        src = int(coarse.node_at(pos)[0])
        if src < 0:
            src = int(coarse.nearest_node(pos))
        if src < 0:
            return
        allowed = coarse.components == coarse.components[src]
        cfg = sim.cfg
        nodes = [
            nd
            for nd in frontier_nodes(
                self.own,
                sim.occupied,
                coarse,
                allowed,
                cfg.min_cluster_cells,
                cfg.max_cluster_extent,
            )  # fmt: skip
            if nd >= 0
        ]
        dist, pred = coarse.distances([src], predecessors=True)
        centres = coarse.centre(np.asarray(nodes, dtype=np.intp)) if nodes else np.empty((0, 2))
        keep = [
            k
            for k, c in enumerate(centres)
            if tuple(np.floor(c).astype(int).tolist()) not in self._banned
            and np.isfinite(dist[0, nodes[k]])
        ]
        if keep:
            idx = np.asarray([nodes[k] for k in keep])
            gain = window_counts(~self.own, centres[keep], int(round(cfg.sensor_range_cells)))
            util = gain / np.maximum(dist[0, idx], 1.0) ** 2
            best = int(idx[int(np.argmax(util))])
            self.path = np.vstack([pos[None], coarse.path(pred[0], best)])
            self.goal_kind = GoalKind.FRONTIER
            self.frontiers_chosen += 1
            return
        home = int(coarse.node_at(sim.base)[0])
        if home >= 0 and np.isfinite(dist[0, home]) and not self.returned:
            self.path = np.vstack([pos[None], coarse.path(pred[0], home)])
            self.goal_kind = GoalKind.HOME
            self.returned = True
            sim.log("return", robot=self.leader)
        else:
            self.path = pos[None].copy()
            self.goal_kind = GoalKind.NONE

    def _carrot(self, sim: ExplorationSim) -> np.ndarray:
        """The point ``speed`` ahead of the leader along its path (its wanted step)."""
        pos = sim.pos[self.leader]
        while len(self.path) > 1 and np.linalg.norm(self.path[0] - pos) < 0.5:
            self.path = self.path[1:]
        budget, here = sim.cfg.speed_cells, pos
        for point in self.path:
            d = float(np.linalg.norm(point - here))
            if d >= budget:
                return here + (point - here) * (budget / max(d, 1e-12)) - pos
            budget -= d
            here = point
        return here - pos

    # -- one step of the Local Steering Strategy for everybody --------------------------
    def _steer(self, sim: ExplorationSim) -> None:
        n, pos = sim.n, sim.pos
        pairs = np.asarray(sim.links, dtype=np.intp).reshape(-1, 2)
        pairs = pairs[(pairs > 0).all(axis=1)] - 1  # robot-robot links (node 0: the BS)
        obs = np.r_[pairs[:, 0], pairs[:, 1]]
        other = np.r_[pairs[:, 1], pairs[:, 0]]
        order = np.lexsort((other, obs))
        obs, other = obs[order], other[order]
        measured = pos[other] - pos[obs]
        indptr = np.r_[0, np.cumsum(np.bincount(obs, minlength=n))]
        wanted = self._carrot(sim)
        steps = team_steps(
            measured, indptr, self.leader, wanted, cost="desired_distance", gamma=self.gamma,
            d0_m=self.d0_cells, d_max_m=self.d_max_cells,
            min_separation_m=self.min_separation_cells, max_step_m=sim.cfg.speed_cells,
            search_directions=True,
        )  # fmt: skip
        steps[~sim.alive] = 0.0
        free = ~sim.occupied
        active = np.linalg.norm(steps, axis=1) > 1e-9
        for _ in range(12):
            idx = np.flatnonzero(active)
            if len(idx) == 0:
                break
            ok = segment_free(free, pos[idx], pos[idx] + steps[idx])
            active[idx[ok]] = False
            steps[idx[~ok]] *= 0.5
        steps[active] = 0.0
        want = float(np.linalg.norm(wanted))
        if want > 1e-9 and np.linalg.norm(steps[self.leader]) < 0.05 * want:
            self.blocked_steps += 1
        for r in np.flatnonzero(np.linalg.norm(steps, axis=1) > 1e-9).tolist():
            target = pos[r] + steps[r]
            at_frontier = (
                r == self.leader
                and self.goal_kind == GoalKind.FRONTIER
                and np.linalg.norm(target - self.path[-1]) < 1e-6
            )
            kind = GoalKind.FRONTIER if at_frontier else GoalKind.RELAY  # a scan on arrival
            sim.assign(r, target, kind, target[None])


class SilentExplorationParams(ExplorationParams):
    """The steering law's parameters (the silent paper's section V); ``d_max`` is the link range."""

    d0_m: float = Field(
        default=11.0, gt=0, le=MAX_LENGTH_M, description="desired distance d0 of cost (13)"
    )
    gamma: float = Field(default=0.2, gt=0, le=100, description="gain of the gradient step (14)")
    min_separation_m: float = Field(
        default=1.0, ge=0, le=MAX_LENGTH_M, description="steps keep robots this far apart"
    )
    leader: int = Field(default=0, ge=0, le=100_000, description="the exploring robot")


@STRATEGIES.register("silent_exploration")
class SilentExploration(ExplorationPlugin):
    """Exploration without communication: a frontier-driven leader, steered followers."""

    name = "silent_exploration"
    Params = SilentExplorationParams

    @classmethod
    def make_policy(cls, params: SilentExplorationParams) -> LeaderFollowerPolicy:
        """The policy with lengths in metres (:meth:`from_scenario` puts them in cells)."""
        return LeaderFollowerPolicy(
            d_max_cells=params.comm_range_m,
            d0_cells=params.d0_m,
            gamma=params.gamma,
            min_separation_cells=params.min_separation_m,
            leader=params.leader,
        )

    @classmethod
    def from_scenario(
        cls, params: Any, scenario: Any, world: World, initial: TeamState, rng: Any
    ) -> SilentExploration:
        src = f"{scenario.source}: strategy.params"
        if params.link_model == "signal":
            raise ScenarioError(
                f"{src}.link_model: the steering law needs a sensing range d_max; use 'los' "
                "or 'disk' (d_max = comm_range_m)"
            )
        if params.scan_steps != 1:
            raise ScenarioError(
                f"{src}.scan_steps: {params.scan_steps}: the steering law never stops a robot "
                "at a frontier to scan; remove scan_steps (or set it to 1)"
            )
        if params.d0_m >= params.comm_range_m:
            raise ScenarioError(
                f"{src}.d0_m: {params.d0_m:g} m is not below the link range comm_range_m = "
                f"{params.comm_range_m:g} m (d_max); lower d0_m"
            )
        if params.leader >= scenario.team.n_robots:
            raise ScenarioError(
                f"{src}.leader: no robot {params.leader} in a team of {scenario.team.n_robots}"
            )
        run = super().from_scenario(params, scenario, world, initial, rng)
        res = run.grid.resolution_m
        run.policy = replace(
            run.policy,
            d_max_cells=run.cfg.link_params["range_cells"],
            d0_cells=params.d0_m / res,
            min_separation_cells=params.min_separation_m / res,
        )
        return run
