"""The "Utility" baseline the recurrent-connectivity paper compares with.

Banfi et al., Sec. VII-A, citing de Hoog et al. [4] (MRESim): a distributed
strategy in which each robot greedily picks a frontier on its own map and
returns towards the BS when the ratio between the area it believes known at
the BS and the area it knows itself drops below ``r`` (0.5 in the paper).
There is no recurrent-connectivity constraint.

Details of this re-implementation:

* a robot's map is its local map, shared with the robots it can currently
  exchange data with (:class:`tether.recurrent.knowledge.Knowledge`);
* "area believed known at the BS" is the size of the BS map the last time
  the robot was connected to the BS; "area known by the robot" is the size
  of its own map (both counted in known cells);
* frontier vertices and gains are those of the BS planner (clusters snapped
  to the coarse grid, ``g(f)`` = unknown cells within sensor range) but on the
  robot's map; utility is eq. (1) with the robot's own geodesic distance;
* ``coordination="greedy"`` (default): robots that can talk coordinate
  greedily: the best (robot, frontier) pair of the group is fixed first, then
  the next, no two robots on one frontier, and frontiers that teammates of the
  group are heading to are not chosen again. This is what de Hoog et al.'s
  implementation (MRESim, which the paper ran) does: a robot ranks the
  (robot, frontier) utilities of itself and of the teammates it communicates
  with and takes the best frontier no better-placed teammate would take
  (``exploration/FrontierExploration.java``, ``chooseFrontier``);
* ``coordination="none"``: every robot picks the best frontier on its own map
  by its own utility, ignoring what teammates pick (the paper's sentence "each
  robot chooses autonomously ... in a greedy fashion" read literally): two
  robots may head to one frontier. Robots that meet still merge maps;
* a robot re-chooses when it reached (and scanned) its frontier, or when its
  goal stopped being a frontier on its map (checked every ``check_every`` steps);
* returning robots head for the BS and resume exploring once connected;
* failed robots (``sim.alive``) are left alone.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tether.recurrent.exploration.sim import ExplorationSim, GoalKind
from tether.recurrent.planning.expgraph import frontier_nodes, window_counts

__all__ = ["UtilityStrategy"]


@dataclass
class UtilityStrategy:
    """Greedy frontier utility with return-to-BS rule ``ratio`` (the paper's ``r``)."""

    ratio: float = 0.5
    coordination: str = "greedy"
    check_every: int = 5
    name: str = "utility"
    choices: int = 0
    returns: int = 0
    planning_times: list[float] = field(default_factory=list)

    def start(self, sim: ExplorationSim) -> None:
        if self.coordination not in ("greedy", "none"):
            raise ValueError(f"coordination must be 'greedy' or 'none' (got {self.coordination!r})")
        self.bs_known = np.full(sim.n, np.count_nonzero(sim.knowledge.global_known), dtype=float)
        self.exhausted = np.zeros(sim.n, dtype=bool)  # no frontier on its map
        self._known_at_exhaustion = np.zeros(sim.n, dtype=np.int64)
        self._choose(sim, np.arange(sim.n))

    def metrics(self) -> dict[str, Any]:
        pt = self.planning_times
        return {
            "plans": self.choices,
            "returns_to_bs": self.returns,
            "planning_time_mean_s": float(np.mean(pt)) if pt else 0.0,
            "planning_time_max_s": float(np.max(pt)) if pt else 0.0,
            "planning_time_total_s": float(np.sum(pt)) if pt else 0.0,
        }

    def update(self, sim: ExplorationSim) -> None:
        know = sim.knowledge
        g = np.count_nonzero(know.global_known)
        self.bs_known[sim.connected] = g
        home = sim.goal_kind == GoalKind.HOME
        # returning robots that reached the BS's network resume exploring
        back = home & sim.connected
        choose = set(np.flatnonzero(back).tolist())
        for r in np.flatnonzero(sim.alive).tolist():
            own = np.count_nonzero(know.local_known[r])
            if self.exhausted[r] and own != self._known_at_exhaustion[r]:
                self.exhausted[r] = False  # its map grew: look again
            if home[r] or sim.connected[r]:
                continue
            if self.bs_known[r] / max(own, 1) < self.ratio or self.exhausted[r]:
                self._go_home(sim, r)
        kinds = sim.goal_kind
        finished = sim.at_goal & sim.scanned & (kinds != GoalKind.HOME) & ~self.exhausted
        choose |= set(np.flatnonzero(finished & sim.alive).tolist())
        choose -= set(np.flatnonzero(~sim.alive).tolist())
        if sim.t % self.check_every == 0:
            for r in np.flatnonzero((kinds == GoalKind.FRONTIER) & ~sim.at_goal & sim.alive):
                if window_counts(~know.local_known[r], sim.goal[r : r + 1], 1)[0] == 0:
                    choose.add(int(r))
        if choose:
            self._choose(sim, np.array(sorted(choose)))

    def _go_home(self, sim: ExplorationSim, r: int) -> None:
        coarse = sim.coarse_known(sim.knowledge.local_known[r])
        src = int(coarse.node_at(sim.pos[r])[0])
        dst = int(coarse.node_at(sim.base)[0])
        if src < 0 or dst < 0:
            return
        _, pred = coarse.distances([src], predecessors=True)
        if src != dst and pred[0, dst] < 0:
            return
        path = np.vstack([sim.pos[r : r + 1], coarse.path(pred[0], dst)])
        sim.assign(r, sim.base, GoalKind.HOME, path)
        self.returns += 1
        sim.log("return", robot=r)

    def _choose(self, sim: ExplorationSim, robots: np.ndarray) -> None:
        import time

        tic = time.perf_counter()
        group_of = {r: k for k, members in enumerate(sim.groups) for r in members}
        by_group: dict[int, list[int]] = {}
        for r in robots.tolist():
            by_group.setdefault(group_of[r], []).append(r)
        for k, members in by_group.items():
            self._choose_group(sim, members, sim.groups[k])
        self.planning_times.append(time.perf_counter() - tic)

    def _choose_group(self, sim: ExplorationSim, members: list[int], group: list[int]) -> None:
        known = sim.knowledge.local_known[members[0]]  # shared inside the group
        coarse = sim.coarse_known(known)
        src = coarse.node_at(sim.pos[members])
        ok = src >= 0
        if not ok.any():
            return
        members = [m for m, good in zip(members, ok, strict=True) if good]
        src = src[ok]
        comp = coarse.components
        allowed = np.zeros(coarse.n_nodes, dtype=bool)
        for s in src:
            allowed |= comp == comp[s]
        nodes = []
        for nd in frontier_nodes(
            known, sim.occupied, coarse, allowed, sim.cfg.min_cluster_cells,
            sim.cfg.max_cluster_extent,
        ):  # fmt: skip
            if nd >= 0 and nd not in nodes:
                nodes.append(nd)
        if self.coordination == "greedy":
            # frontiers already targeted by teammates of the group are taken
            taken = {
                int(coarse.node_at(sim.goal[r])[0])
                for r in group
                if r not in members and sim.goal_kind[r] == GoalKind.FRONTIER
            }
            nodes = [nd for nd in nodes if nd not in taken]
        if not nodes:
            for r in members:
                self._exhaust(sim, r)
            return
        nodes_arr = np.asarray(nodes)
        pos = coarse.centre(nodes_arr)
        gain = window_counts(~known, pos, int(round(sim.cfg.sensor_range_cells)))
        geo = coarse.geodesics(src, lazy=True)
        d = geo.dist[:, nodes_arr]
        util = gain[None, :] / np.maximum(d, 1.0) ** 2  # eq. (1) per robot
        util[~np.isfinite(d)] = -1.0
        if self.coordination == "none":  # each robot on its own: its best frontier
            for k, r in enumerate(members):
                f = int(np.argmax(util[k]))
                if util[k, f] < 0:
                    self._exhaust(sim, r)
                    continue
                path = np.vstack([sim.pos[r : r + 1], geo.path(k, int(nodes_arr[f]))])
                sim.assign(r, pos[f], GoalKind.FRONTIER, path)
                self.choices += 1
            return
        free_r = list(range(len(members)))
        free_f = set(range(len(nodes)))
        while free_r and free_f:
            cols = sorted(free_f)
            sub = util[np.ix_(free_r, cols)]
            i, j = np.unravel_index(int(np.argmax(sub)), sub.shape)
            if sub[i, j] < 0:
                break
            k, f = free_r[i], cols[j]
            r = members[k]
            path = np.vstack([sim.pos[r : r + 1], geo.path(k, int(nodes_arr[f]))])
            sim.assign(r, pos[f], GoalKind.FRONTIER, path)
            self.choices += 1
            free_r.remove(k)
            free_f.discard(f)
        for k in free_r:
            self._exhaust(sim, members[k])

    def _exhaust(self, sim: ExplorationSim, r: int) -> None:
        """No frontier left for ``r`` on its map: stop (and go home if disconnected)."""
        self.exhausted[r] = True
        self._known_at_exhaustion[r] = np.count_nonzero(sim.knowledge.local_known[r])
        if sim.goal_kind[r] == GoalKind.FRONTIER:
            sim.stop(r)
