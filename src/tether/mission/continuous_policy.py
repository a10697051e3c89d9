"""The continuous-connectivity paradigm on the exploration simulator: a policy.

:class:`ContinuousPolicy` drives the exploration simulator's robots with the
continuous-connectivity controller (:class:`~tether.mission.fixed_base.
FixedBaseMultiTarget`: ``multi_target`` with the base station as a fixed node of the
weighted graph) and gives every explorer its targets online from the frontiers of the
map it holds (:class:`~tether.mission.frontier_targets.FrontierPicker`).

Each step of the simulator (``sim.dt_s``) the policy

1. gives a frontier to every robot without a target and drops targets whose frontier
   has been explored meanwhile (they expire, as a target past its ``timeout_s``);
2. runs the controller for the step's control periods (``control_period_s`` each);
3. hands every robot's trajectory of the step to the simulator (:meth:`ExplorationSim.
   assign`), which moves the robot along it at the next step, senses with the mission's
   depth sensor along its heading, and shares maps over the mission's links, as for
   every paradigm. A robot that arrives at a target (becomes an anchor) takes a full
   360 degree scan there, as every paradigm's robots do at a frontier.

Paths of the controller's planner (A* on cells of ``Rgrid``) run through the free space
*known* to the team: unknown cells count as obstacles.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from tether.continuous.exploration.params import MultiTargetParams
from tether.continuous.exploration.roles import ANCHOR
from tether.mission.fixed_base import FixedBaseMultiTarget
from tether.mission.frontier_targets import FrontierPicker
from tether.paths.astar import planning_grid
from tether.recurrent.exploration.sim import ExplorationSim, GoalKind
from tether.sim import StepContext, TeamState
from tether.world.grid import OccupancyGrid
from tether.world.world import World

__all__ = ["ContinuousPolicy"]

#: the controller's events the run keeps (the others, roles and elections, are many)
KEPT_EVENTS = ("target_taken", "target_reached", "target_dropped", "help_requested", "stall")


@dataclass
class ContinuousPolicy:
    """Frontier targets for ``multi_target`` with the base station as a fixed node.

    Parameters
    ----------
    params
        The controller's parameters.
    world
        The mission's world (metres; the true obstacles the connectivity force sees).
    control_period_s
        The controller's period; a simulator step runs ``dt_s / control_period_s`` of them.
    stay_s
        ``Delta t``: how long an explorer stays at a target.
    target_timeout_s
        A robot that has not reached its target this long after taking it drops it.
    """

    params: MultiTargetParams
    world: World | None
    control_period_s: float = 0.1
    stay_s: float = 3.0
    target_timeout_s: float | None = None
    dt_s: float = 1.0
    seed: int = 0
    name: str = "continuous_exploration"

    # -- set up --------------------------------------------------------------------------
    def start(self, sim: ExplorationSim) -> None:
        assert self.world is not None and self.world.grid is not None
        grid = self.world.grid
        self.grid: OccupancyGrid = grid
        n = sim.n
        self.n = n
        self.periods = max(int(round(self.dt_s / self.control_period_s)), 1)
        self.period_s = self.dt_s / self.periods
        self.ctrl = FixedBaseMultiTarget(self.params, n)
        q0 = np.vstack([self.to_m(sim.pos), self.to_m(sim.base)[None]])
        self.state = TeamState.at_rest(q0)
        self.rng = np.random.default_rng(self.seed)
        self.ctrl.reset(self.world, self.state, self.rng)
        cfg = sim.cfg
        rz_cells = self.params.rz_m / grid.resolution_m
        self.picker = FrontierPicker(
            sim.occupied, cfg.coarse_factor, int(round(cfg.sensor_range_cells)),
            spacing_cells=2.0 * rz_cells, min_cluster_cells=cfg.min_cluster_cells,
            max_cluster_extent=cfg.max_cluster_extent,
        )  # fmt: skip
        self.target_cell = np.full((n, 2), np.nan)  # each robot's frontier (nan: none)
        self.period = 0
        self.frontiers_given = 0
        self.stale_dropped = 0
        self.dropped: dict[str, int] = {}
        self.lambda2_series: list[float] = [self.ctrl.lambda2()]
        self._map_version = -1
        self._anchored = np.zeros(n, dtype=bool)
        self.update(sim)

    def to_m(self, cells: np.ndarray) -> np.ndarray:
        return self.grid.origin_m + np.asarray(cells, dtype=float) * self.grid.resolution_m

    def to_cells(self, metres: np.ndarray) -> np.ndarray:
        return (np.asarray(metres, dtype=float) - self.grid.origin_m) / self.grid.resolution_m

    # -- targets -------------------------------------------------------------------------
    def _known(self, sim: ExplorationSim, robot: int) -> np.ndarray:
        return sim.knowledge.local_known[robot]

    def _retire(self, sim: ExplorationSim) -> None:
        """Forget frontiers whose target ended; let explored frontiers expire."""
        pl = self.ctrl.planner
        t_s = self.period * self.period_s
        for r in range(self.n):
            if np.isnan(self.target_cell[r, 0]):
                continue
            z = pl.target[r]
            if z is None and not self.ctrl.targets.queues[r]:  # reached or dropped
                self.picker.ban(self.target_cell[r])
                self.target_cell[r] = np.nan
            elif (
                z is not None
                and pl.role[r] != ANCHOR
                and not self.picker.still_frontier(self._known(sim, r), self.target_cell[r])
            ):
                z.timeout_s = max(t_s - pl.taken_at[r] - 1e-9, 0.0)  # expires at once
                self.stale_dropped += 1

    def _give(self, sim: ExplorationSim) -> None:
        """A frontier for every robot with no target (from the map it holds)."""
        needy = [r for r in range(self.n) if np.isnan(self.target_cell[r, 0])]
        if not needy:
            return
        taken = self.target_cell[~np.isnan(self.target_cell[:, 0])]
        chosen = []
        for r in needy:
            got = self.picker.choose(self._known(sim, r), sim.pos, [r], taken)
            chosen += got
            if got:
                taken = np.vstack([taken, got[0].cell[None]])
        if not chosen:
            return
        self._plan_on_known(sim)
        t_s = self.period * self.period_s
        for c in chosen:
            self.target_cell[c.robot] = c.cell
            self.ctrl.add_target(c.robot, self.to_m(c.cell), self.stay_s, appear_s=t_s,
                                 timeout_s=self.target_timeout_s)  # fmt: skip
            self.frontiers_given += 1

    def _plan_on_known(self, sim: ExplorationSim) -> None:
        """The planner's grid from the known free space (unknown cells are obstacles)."""
        version = sim.knowledge.global_version
        if version == self._map_version:
            return
        self._map_version = version
        known = sim.knowledge.global_known | sim.knowledge.local_known.any(axis=0)
        blocked = sim.occupied | ~known
        grid = OccupancyGrid(blocked, self.grid.resolution_m, self.grid.origin_m)
        pl = self.ctrl.planner
        pl._planning = planning_grid(grid, cell_m=pl.r_grid_m, inflate_m=pl.inflate_m)

    # -- one simulator step --------------------------------------------------------------
    def update(self, sim: ExplorationSim) -> None:
        self._retire(sim)
        self._give(sim)
        q, v = self.state.positions, self.state.velocities
        trail = []
        for _ in range(self.periods):
            ctx = StepContext(self.period, self.period * self.period_s, self.period_s,
                              self.world, TeamState(q, v), None, self.rng)  # fmt: skip
            out = self.ctrl.step(ctx)
            q, v = out.positions, out.velocities
            self.period += 1
            trail.append(q[: self.n].copy())
        self.lambda2_series.append(self.ctrl.lambda2())
        self.state = TeamState(q, v)
        for event in self.ctrl.drain_events():
            if event.get("kind") == "target_dropped":
                reason = str(event.get("reason"))
                self.dropped[reason] = self.dropped.get(reason, 0) + 1
            if event.get("kind") in KEPT_EVENTS:
                sim.log(event["kind"], **{k: w for k, w in event.items()
                                          if k not in ("kind", "step")})  # fmt: skip
        anchored = self.ctrl.planner.role[: self.n] == ANCHOR
        arrived = anchored & ~self._anchored
        self._anchored = anchored
        cells = self.to_cells(np.stack(trail))  # (periods, n, 2)
        moved = np.linalg.norm(cells[-1] - sim.pos, axis=1) > 1e-9
        for r in np.flatnonzero(moved | arrived).tolist():
            kind = GoalKind.FRONTIER if arrived[r] else GoalKind.RELAY
            sim.assign(r, cells[-1, r], kind, cells[:, r])

    # -- results -------------------------------------------------------------------------
    def metrics(self) -> dict[str, Any]:
        ctrl = self.ctrl.metrics()
        keep = (
            "controller_success", "min_lambda2_weighted", "guard", "guard_interventions",
            "safe_set_exits", "tolerance_misses", "stalls", "max_speed_mps",
            "speed_bound_mps", "min_robot_distance_m", "min_obstacle_clearance_m",
            "targets_total", "targets_reached", "targets_dropped", "targets_pending",
            "replans", "elections", "help_requests",
        )  # fmt: skip
        out = {k: ctrl.get(k) for k in keep}
        out["frontiers_given"] = self.frontiers_given
        out["frontiers_explored_before_reached"] = self.stale_dropped
        out["targets_dropped_by_reason"] = dict(sorted(self.dropped.items()))
        out["control_periods"] = self.period
        return out
