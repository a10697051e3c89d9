"""Grid exploration simulator for the recurrent-connectivity paper.

Recurrent-connectivity paper (Banfi et al., Sec. VII-A; MRESim-like): ``m``
robots with a depth sensor explore a 2-D occupancy map from a base station
(BS). Each step:

1. robots advance ``speed_cells`` along their paths (paths run through known
   free space, so they are always valid);
2. moving robots sense a 60 degree fan along their heading; a robot that
   reaches a frontier goal takes a complete rotation (360 degrees);
3. communication links among the BS and the robots are evaluated with the
   link model on the *true* map (the planner's ``C^t`` uses the same model on
   the BS's *known* map, which is conservative); robots in one component
   exchange maps, and a component holding the BS flushes everything it knows
   to the BS (data gathered while disconnected is delivered on reconnection);
4. the policy (the BS planner of :mod:`tether.recurrent.replanning` or the
   Utility baseline of :mod:`tether.recurrent.baseline_utility`) reacts.

Faults: ``ExplorationConfig.failures`` maps a robot to the step at which it
fails (fail-stop): from that step on it stands still, senses nothing and has
no link (what it knew and did not deliver is lost). :meth:`ExplorationSim.fail`
does the same on demand. Policies read ``sim.alive``.

The sim is a world model with no time loop or history of its own: the core
loop (:func:`tether.sim.simulate`) steps it through the adapter of
:mod:`tether.recurrent.exploration.run`, which records it like every run.

Positions are continuous cell coordinates (cell ``(ix, iy)`` covers
``[ix, ix+1) x [iy, iy+1)``); one step is one second.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np
from scipy import ndimage

from tether.graph import components
from tether.paths.geodesic import CoarseGrid
from tether.recurrent.exploration.knowledge import Knowledge
from tether.registry import LINK_MODELS
from tether.sensing.depth import DepthSensor
from tether.sensing.links import LinkModel, link_pairs

__all__ = [
    "ExplorationConfig",
    "ExplorationPolicy",
    "ExplorationSim",
    "GoalKind",
    "random_base",
    "start_cells",
]


class GoalKind:
    """What a robot's goal is (ints so they fit in arrays)."""

    NONE = 0  # no goal (idle where it stands)
    RELAY = 1  # a non-frontier vertex of a configuration
    FRONTIER = 2  # a frontier: take a full scan on arrival
    FAKE = 3  # a "fake" frontier (Sec. V): a leftover robot next to the configuration
    HOME = 4  # Utility baseline: heading back towards the BS


@dataclass
class ExplorationConfig:
    """Physical parameters of an exploration run (paper defaults, Sec. VII-A)."""

    n_robots: int = 12
    steps: int = 900
    speed_cells: float = 4.0
    fov_deg: float = 60.0
    sensor_range_cells: float = 50.0
    sensor_resolution_deg: float = 1.0
    link_model: str = "los"
    link_params: dict[str, Any] = field(default_factory=lambda: {"range_cells": 150.0})
    coarse_factor: int = 3
    min_cluster_cells: int = 4
    max_cluster_extent: int = 30
    scan_steps: int = 1  # steps a full rotation takes
    failures: dict[int, int] = field(default_factory=dict)  # robot -> step it fails at
    coverage_goal: float | None = None  # stop once the BS knows this share of the area


class ExplorationPolicy(Protocol):
    """The decision-making of an exploration run: the BS planner or the Utility baseline.

    :class:`ExplorationSim` calls ``update`` once per step after moving,
    sensing and communicating; ``start`` once after the initial scans.
    """

    name: str

    def start(self, sim: ExplorationSim) -> None: ...

    def update(self, sim: ExplorationSim) -> None: ...

    def metrics(self) -> dict[str, Any]: ...


def _reachable_free(occupied: np.ndarray, start: np.ndarray) -> np.ndarray:
    """True free cells 8-connected to ``start`` (the area the team could ever explore)."""
    lab, _ = ndimage.label(~occupied, structure=np.ones((3, 3), bool))
    c = np.floor(start).astype(int)
    return lab == lab[c[0], c[1]]


def random_base(occupied: np.ndarray, coarse_factor: int, rng: np.random.Generator) -> np.ndarray:
    """A random BS position on a traversable coarse cell of the largest free region."""
    cg = CoarseGrid(~occupied, coarse_factor)
    comp = cg.components
    big = np.argmax(np.bincount(comp))
    cand = np.flatnonzero(comp == big)
    return cg.centre(int(rng.choice(cand)))[0]


def start_cells(
    occupied: np.ndarray, base: np.ndarray, n: int, coarse_factor: int
) -> tuple[np.ndarray, np.ndarray]:
    """The BS snapped to the nearest traversable coarse cell centre, and the robots' starts.

    Robots start on the ``n`` traversable coarse cells geodesically closest to
    the BS (repeating the closest one if there are fewer). Cell coordinates.
    """
    true_coarse = CoarseGrid(~np.asarray(occupied, dtype=bool), coarse_factor)
    bnode = true_coarse.nearest_node(np.asarray(base, float))
    if bnode < 0:
        raise ValueError("the map has no traversable cell for the base station")
    d = true_coarse.distances([bnode])[0]
    order = np.argsort(d, kind="stable")
    order = order[np.isfinite(d[order])][:n]
    starts = true_coarse.centre(order)
    if len(starts) < n:
        starts = np.vstack([starts, np.repeat(starts[:1], n - len(starts), axis=0)])
    return true_coarse.centre(bnode)[0], starts.astype(float)


class ExplorationSim:
    """State of an exploration run; strategies read and command it.

    Parameters
    ----------
    occupied
        True map ``(nx, ny)``.
    base
        BS position (cell coordinates); snapped to the nearest traversable
        coarse cell centre.
    strategy
        The decision-making (:class:`ExplorationPolicy`).
    config
        Physical parameters.
    starts
        ``(n, 2)`` start positions (cell coordinates); the BS is then used as given,
        not snapped. Default: the coarse cells nearest the BS (:func:`start_cells`).
    """

    def __init__(
        self,
        occupied: np.ndarray,
        base: np.ndarray,
        strategy: ExplorationPolicy,
        config: ExplorationConfig | None = None,
        starts: np.ndarray | None = None,
    ) -> None:
        self.cfg = config or ExplorationConfig()
        self.occupied = np.asarray(occupied, dtype=bool)
        self.shape = self.occupied.shape
        self.strategy = strategy
        self.sensor = DepthSensor(
            self.cfg.fov_deg, self.cfg.sensor_range_cells, self.cfg.sensor_resolution_deg
        )
        self.link: LinkModel = LINK_MODELS.get(self.cfg.link_model)(**self.cfg.link_params)
        n = self.cfg.n_robots
        self.n = n
        if starts is None:
            self.base, starts = start_cells(self.occupied, base, n, self.cfg.coarse_factor)
        else:
            self.base = np.asarray(base, dtype=float).copy()
            starts = np.array(starts, dtype=float).reshape(n, 2)
        self.free_region = _reachable_free(self.occupied, self.base)
        self.free_total = int(self.free_region.sum())
        self.pos = starts
        self.heading = np.zeros(n)
        self.paths: list[np.ndarray] = [self.pos[i : i + 1].copy() for i in range(n)]
        self.path_idx = np.zeros(n, dtype=int)
        self.goal = self.pos.copy()
        self.goal_kind = np.full(n, GoalKind.NONE, dtype=int)
        self.at_goal = np.ones(n, dtype=bool)
        self.scanned = np.ones(n, dtype=bool)
        self.delivered = np.ones(n, dtype=bool)
        self.wait_until = np.zeros(n, dtype=int)  # no motion before this step
        self.scan_left = np.zeros(n, dtype=int)
        self.alive = np.ones(n, dtype=bool)
        self.failed_at = np.full(n, -1, dtype=int)  # step of the failure, -1 if alive
        self.goal_at_failure = np.full((n, 2), np.nan)  # the goal it was heading to
        self.moved = np.zeros(n, dtype=bool)  # advanced along its path in the last step
        self.knowledge = Knowledge(self.shape, n)
        # explored_fraction() of the BS map version it was counted for
        self._explored: tuple[int, float] = (-1, 0.0)
        self.connected = np.ones(n, dtype=bool)
        self.groups: list[list[int]] = [list(range(n))]
        self.t = 0
        self.events: list[dict[str, Any]] = []
        self.timing = {"move": 0.0, "sense": 0.0, "comm": 0.0, "strategy": 0.0}
        # the cells each robot sensed in the last step (robot, flat indices), for metrics
        self.sensed: list[tuple[int, np.ndarray]] = []
        # initial full scans at the start positions, shared with the BS
        for r, cells in enumerate(self.sensor.scan(self.occupied, self.pos, self.heading, True)):
            self.knowledge.observe(r, cells)
            self.sensed.append((r, cells))
        self._communicate()

    # ------------------------------------------------------------------ commands
    def assign(
        self, robot: int, goal: np.ndarray, kind: int, path: np.ndarray, delay: int = 0
    ) -> None:
        """Send ``robot`` along ``path`` (``(k, 2)`` waypoints ending at ``goal``).

        The robot stays where it is for ``delay`` steps after the current one.
        """
        path = np.atleast_2d(np.asarray(path, dtype=float))
        if len(path) == 0:
            path = self.pos[robot : robot + 1].copy()
        self.paths[robot] = path
        self.path_idx[robot] = 0
        self.goal[robot] = np.asarray(goal, dtype=float)
        self.goal_kind[robot] = kind
        arrived = bool(np.allclose(self.pos[robot], self.goal[robot]))
        self.at_goal[robot] = arrived
        self.scanned[robot] = kind != GoalKind.FRONTIER
        self.delivered[robot] = False
        self.scan_left[robot] = (
            self.cfg.scan_steps if (arrived and kind == GoalKind.FRONTIER) else 0
        )
        # robots move from the next step on; a plan that took ``delay`` steps
        # (Fig. 4a) holds them ``delay`` more steps
        self.wait_until[robot] = self.t + 1 + int(delay)

    def hold_steps(self, robot: int) -> int:
        """Steps after the current one that ``robot`` still stands still.

        ``0`` right after an :meth:`assign` with ``delay=0`` (the robot moves
        at the next step, like any robot already under way), ``delay`` after
        ``assign(..., delay=delay)``.
        """
        return max(int(self.wait_until[robot]) - self.t - 1, 0)

    def stop(self, robot: int) -> None:
        """Stop where the robot stands (its position becomes its goal)."""
        self.assign(robot, self.pos[robot].copy(), GoalKind.NONE, self.pos[robot : robot + 1])
        self.at_goal[robot] = True

    def fail(self, robot: int) -> None:
        """Fail-stop ``robot`` now: it stops, senses nothing and drops its links for good."""
        if not self.alive[robot]:
            return
        self.alive[robot] = False
        self.failed_at[robot] = self.t
        self.goal_at_failure[robot] = self.goal[robot]
        self.stop(robot)
        self.connected[robot] = False
        self.log("failure", robot=int(robot))

    def known_by_bs(self) -> np.ndarray:
        return self.knowledge.global_known

    def coarse_known(self, known: np.ndarray | None = None) -> CoarseGrid:
        """Coarse geodesic grid of a known map (default: the BS's)."""
        k = self.knowledge.global_known if known is None else known
        return CoarseGrid(k & ~self.occupied, self.cfg.coarse_factor)

    def remaining_distance(self, robot: int) -> float:
        """Length (cells) of the rest of the robot's path."""
        path = self.paths[robot]
        k = self.path_idx[robot]
        if k >= len(path):
            return 0.0
        d = np.linalg.norm(path[k] - self.pos[robot])
        if k + 1 < len(path):
            d += np.linalg.norm(np.diff(path[k:], axis=0), axis=1).sum()
        return float(d)

    def log(self, kind: str, **data: Any) -> None:
        self.events.append({"step": self.t, "kind": kind, **data})

    # ------------------------------------------------------------------ stepping
    def _move(self) -> np.ndarray:
        """Advance robots along their paths; returns the mask of robots that moved."""
        moved = np.zeros(self.n, dtype=bool)
        speed = self.cfg.speed_cells
        for r in range(self.n):
            if self.at_goal[r] or self.t < self.wait_until[r] or not self.alive[r]:
                continue
            path = self.paths[r]
            budget = speed
            p = self.pos[r]
            k = self.path_idx[r]
            while budget > 1e-9 and k < len(path):
                seg = path[k] - p
                L = float(np.hypot(seg[0], seg[1]))
                if budget >= L:
                    p = path[k].copy()
                    budget -= L
                    k += 1
                else:
                    p = p + seg * (budget / L)
                    budget = 0.0
                if L > 1e-9:
                    self.heading[r] = np.arctan2(seg[1], seg[0])
            moved[r] = True
            self.pos[r] = p
            self.path_idx[r] = k
            if k >= len(path):
                self.pos[r] = path[-1]
                self.at_goal[r] = True
                if self.goal_kind[r] == GoalKind.FRONTIER:
                    self.scan_left[r] = self.cfg.scan_steps
        return moved

    def _sense(self, moved: np.ndarray) -> None:
        scanning = (self.scan_left > 0) & self.alive
        who = np.flatnonzero(moved | scanning)
        if len(who) == 0:
            return
        full = scanning[who]
        seen = self.sensor.scan(self.occupied, self.pos[who], self.heading[who], full)
        for r, cells in zip(who, seen, strict=True):
            self.knowledge.observe(int(r), cells)
            self.sensed.append((int(r), cells))
        self.scan_left[scanning] -= 1
        done = scanning & (self.scan_left == 0)
        self.scanned[done] = True

    def _communicate(self) -> None:
        nodes = np.vstack([self.base[None], self.pos])
        pairs = link_pairs(self.link, ~self.occupied, nodes)
        if not self.alive.all():  # failed robots have no link
            dead = np.flatnonzero(~self.alive) + 1
            pairs = pairs[~np.isin(pairs, dead).any(axis=1)]
        _, lab = components(len(nodes), pairs)
        self.connected = lab[1:] == lab[0]
        groups: dict[int, list[int]] = {}
        for r in range(self.n):
            groups.setdefault(int(lab[r + 1]), []).append(r)
        keys = sorted(groups)
        self.groups = [groups[k] for k in keys]
        self.knowledge.exchange(self.groups, [k == lab[0] for k in keys])
        self.links = pairs
        # a robot's data is at the BS once it finished at its goal while connected
        self.delivered |= self.connected & self.at_goal & self.scanned

    def explored_fraction(self) -> float:
        """Share of the reachable free area known at the BS.

        Counted once per version of the BS map (``Knowledge.global_version``, bumped
        whenever it grows).
        """
        version = self.knowledge.global_version
        if self._explored[0] != version:
            known = self.knowledge.global_known
            share = np.count_nonzero(known & self.free_region) / self.free_total
            self._explored = (version, share)
        return self._explored[1]

    def step(self) -> None:
        """Advance by one step: move, sense, communicate, then the policy decides."""
        self.t += 1
        self.sensed = []
        for r, step in self.cfg.failures.items():
            if step == self.t:
                self.fail(int(r))
        tic = time.perf_counter()
        moved = self._move()
        self.moved = moved
        t1 = time.perf_counter()
        self._sense(moved)
        t2 = time.perf_counter()
        self._communicate()
        t3 = time.perf_counter()
        self.strategy.update(self)
        t4 = time.perf_counter()
        for key, dt in zip(
            ("move", "sense", "comm", "strategy"),
            (t1 - tic, t2 - t1, t3 - t2, t4 - t3),
            strict=True,
        ):
            self.timing[key] += dt
