"""Algorithm 1 (planning) and the start-up procedure: roles, targets, paths (Secs. 3.2-3.4).

Four roles: ``connector`` (no target, ``f_i = 0``), ``prime`` (the one traveler
whose target has priority), ``secondary`` (travelers scaled by ``rho``) and
``anchor`` (within ``Rz`` of its target, staying for ``Delta t``). Each robot
decides from its own position, its own target queue and the election's outcome
(:mod:`tether.continuous.exploration.election`). Paths are A* on the inflated 3-D grid of
cell ``Rgrid`` smoothed by a B-spline (:mod:`tether.paths`), sampled for the
control loop (:mod:`tether.continuous.exploration.tracking`).

Beyond the paper: a target that cannot be reached (no path) or that expires
(``timeout_s``) is dropped with an event and the robot moves on to its next
target, so no single target can stall the team (the paper's closing
suggestion); a prime traveler that drops its target hands its role on through an
election, exactly as one that reached it.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from tether import floats, jit
from tether.continuous.exploration.targets import Target, TargetBook
from tether.continuous.exploration.tracking import PathSet, TrackedPath
from tether.paths.astar import plan_path, planning_grid
from tether.paths.bspline import smooth_path
from tether.world.world import World

CONNECTOR, PRIME, SECONDARY, ANCHOR = range(4)
ROLE_NAMES = ("connector", "prime", "secondary", "anchor")

Emit = Callable[..., None]


class RolePlanner:
    """Per-robot roles, current targets and paths, and the transitions of Algorithm 1.

    Parameters
    ----------
    world
        The scene (paths are planned on its grid).
    book
        The target queues.
    r_grid_m, inflate_m, rz_m, r_gamma_m
        Planning cell and inflation, anchoring radius, replanning distance.
    stall_timeout_s
        A prime traveler whose remaining path has not shrunk by ``r_grid_m`` for
        this long drops its target (``None``: never).
    replan_stalled_s
        A prime traveler whose remaining path has not shrunk by ``r_grid_m`` for
        this long plans its path again from where it is, and again after each further
        ``replan_stalled_s`` without progress (``None``: never; line 18 of Algorithm 1,
        which the paper applies to secondary travelers only).
    emit
        ``emit(kind, robot, **data)`` records an event.
    """

    def __init__(
        self,
        world: World,
        book: TargetBook,
        *,
        r_grid_m: float,
        inflate_m: float,
        rz_m: float,
        r_gamma_m: float,
        stall_timeout_s: float | None,
        emit: Emit,
        replan_stalled_s: float | None = None,
    ) -> None:
        n = len(book.queues)
        self.world = world
        self.book = book
        self.r_grid_m = r_grid_m
        self.rz_m = rz_m
        self.r_gamma_m = r_gamma_m
        self.inflate_m = inflate_m
        self.stall_timeout_s = stall_timeout_s
        self.replan_stalled_s = replan_stalled_s
        self.emit = emit
        self.role = np.full(n, CONNECTOR)
        self.target: list[Target | None] = [None] * n  # written only through _assign
        self._goal_m = np.full((n, world.dim), np.nan)  # the targets' positions (nan: none)
        self._has_target = np.zeros(n, dtype=bool)
        self._paths: list[TrackedPath | None] = [None] * n
        self._set: tuple[np.ndarray, PathSet] | None = None
        self.inside_since = np.full(n, np.nan)  # when the robot entered Rz of its target
        self.taken_at = np.full(n, np.nan)  # when the current target was taken up
        self.explorer = np.zeros(n, dtype=bool)  # had at least one target
        self.reached = 0
        self.dropped = 0
        self.replans = 0
        self.progress = np.full(n, np.inf)  # the prime's best remaining length so far
        self.progress_at = np.full(n, np.nan)  # ... and when it last shrank by r_grid_m
        self.replanned_at = np.full(n, np.nan)  # the prime's last replan while stalled
        self._planning = None
        if world.grid is not None:
            self._planning = planning_grid(world, cell_m=r_grid_m, inflate_m=inflate_m)

    # -- paths -----------------------------------------------------------------------
    @property
    def path(self) -> tuple[TrackedPath | None, ...]:
        """Each robot's current path (``None``: not traveling)."""
        return tuple(self._paths)

    def set_path(self, robot: int, path: TrackedPath | None) -> None:
        self._paths[robot] = path
        self._set = None

    def path_set(self) -> tuple[np.ndarray, PathSet]:
        """The robots with a path and their paths concatenated (cached until one changes)."""
        if self._set is None:
            robots = np.array([i for i, p in enumerate(self._paths) if p is not None], int)
            self._set = (robots, PathSet([self._paths[i] for i in robots]))
        return self._set

    # -- helpers ---------------------------------------------------------------------
    def _assign(self, robot: int, z: Target | None) -> None:
        """Set ``robot``'s current target (and the arrays that mirror the list)."""
        self.target[robot] = z
        self._has_target[robot] = z is not None
        self._goal_m[robot] = np.nan if z is None else z.position_m

    def set_role(self, robot: int, role: int, t_s: float) -> None:
        if role == PRIME:  # a new prime starts its progress watch
            self.progress[robot], self.progress_at[robot] = np.inf, np.nan
            self.replanned_at[robot] = np.nan
        if self.role[robot] != role:
            self.emit("role", robot, t_s=t_s, old=ROLE_NAMES[self.role[robot]],
                      new=ROLE_NAMES[role])  # fmt: skip
            self.role[robot] = role

    def plan(self, robot: int, q: np.ndarray) -> TrackedPath | None:
        """A* (cell ``Rgrid``) and B-spline from ``q`` to the robot's target; ``None`` if none."""
        goal = self.target[robot].position_m
        waypoints = plan_path(self.world, q, goal, cell_m=self.r_grid_m,
                              inflate_m=self.inflate_m, planning=self._planning)  # fmt: skip
        if waypoints is None:
            return None
        return TrackedPath.from_spline(smooth_path(waypoints, self.world, planning=self._planning))

    def distance_to_target(self, q: np.ndarray) -> np.ndarray:
        """``|q_i - z_i|`` per robot (``inf``: no target).

        With kernels on (:func:`tether.jit.enabled`), one row-wise norm over the array of
        target positions; otherwise robot by robot (the reference). ``numpy.linalg.norm``
        sums a row's squares in coordinate order either way (``tests/test_roles_fast.py``).
        """
        if jit.enabled():
            d = np.linalg.norm(q - self._goal_m, axis=1)
            d[~self._has_target] = np.inf
            return d
        d = np.full(len(q), np.inf)
        for i, z in enumerate(self.target):
            if z is not None:
                d[i] = floats.norm(q[i] - z.position_m)
        return d

    def on_path(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Distance to the path and remaining length ``d_gamma`` per robot (``inf``: no path)."""
        dist, remaining = np.full(len(q), np.inf), np.full(len(q), np.inf)
        robots, paths = self.path_set()
        if len(robots) and jit.enabled():  # the kernel's closest points (kept for the election)
            _, _, dist[robots], remaining[robots], _, _ = paths.closest(q[robots])
        elif len(robots):
            st = paths.states(q[robots], 0.0)
            dist[robots], remaining[robots] = st.distance_m, st.remaining_m
        return dist, remaining

    def drop(self, robot: int, t_s: float, reason: str) -> None:
        z = self.target[robot]
        self.emit("target_dropped", robot, t_s=t_s, target=z.id, reason=reason)
        self.dropped += 1
        self._assign(robot, None)
        self.set_path(robot, None)
        self.inside_since[robot] = np.nan

    def take_next(self, robot: int, q: np.ndarray, t_s: float) -> bool:
        """Take the next available target with a path; drop unreachable ones. True if taken."""
        while (z := self.book.take(robot, t_s)) is not None:
            self._assign(robot, z)
            self.explorer[robot] = True
            self.taken_at[robot] = t_s
            path = self.plan(robot, q)
            if path is not None:
                self.set_path(robot, path)
                where = z.position_m.tolist()
                self.emit("target_taken", robot, t_s=t_s, target=z.id, position_m=where,
                          path_m=round(path.length_m, 3))  # fmt: skip
                return True
            self.drop(robot, t_s, "unreachable")
        return False

    # -- the start-up procedure and Algorithm 1 ---------------------------------------
    def start_up(self, q: np.ndarray) -> None:
        """Robots with a target plan a path and stand as candidates of the first election."""
        for i in range(len(q)):
            if self.take_next(i, q[i], 0.0):
                self.set_role(i, SECONDARY, 0.0)

    def update(self, q: np.ndarray, t_s: float) -> np.ndarray:
        """Algorithm 1 for every robot; returns who wants a prime election (line 14)."""
        dist = self.distance_to_target(q)
        off_path, remaining = self.on_path(q)
        self._watch(remaining, t_s, q)
        wants = np.zeros(len(q), dtype=bool)
        # Python scalars for the loop (the same float64 values): robot i's iteration
        # changes only robot i's role, distance and times, read before it starts
        roles, dist_l, off_l = self.role.tolist(), dist.tolist(), off_path.tolist()
        for i in range(len(q)):
            role, z = roles[i], self.target[i]
            if role == CONNECTOR and not self.book.queues[i]:
                continue  # nothing to take up (take_next would find nothing)
            if z is not None and z.timeout_s is not None and role in (PRIME, SECONDARY) \
                    and t_s - self.taken_at[i] > z.timeout_s:  # fmt: skip
                self.drop(i, t_s, "expired")
                z = None
                if role == SECONDARY:
                    self.set_role(i, CONNECTOR, t_s)
                    role = CONNECTOR
            if role == CONNECTOR:
                if self.take_next(i, q[i], t_s):
                    self.set_role(i, SECONDARY, t_s)
            elif role == PRIME:
                if z is None or dist_l[i] < self.rz_m:  # reached (or dropped): succession
                    if self._paths[i] is not None:
                        self.set_path(i, None)
                    if z is not None and np.isnan(self.inside_since[i]):
                        self.inside_since[i] = t_s
                    wants[i] = True
            elif role == SECONDARY:
                self._secondary(i, q[i], dist_l[i], off_l[i], t_s)
            elif role == ANCHOR and t_s - self.inside_since[i] >= z.stay_s - 1e-9:
                self.emit("target_reached", i, t_s=t_s, target=z.id)
                self.reached += 1
                self._assign(i, None)
                self.inside_since[i] = np.nan
                self.set_role(i, CONNECTOR, t_s)
        return wants

    def _watch(self, remaining: np.ndarray, t_s: float, q: np.ndarray) -> None:
        """The prime's progress watchdog: replan, then drop, a target it cannot get closer to."""
        for i in np.flatnonzero(self.role == PRIME):
            if not np.isfinite(remaining[i]):
                continue
            if remaining[i] < self.progress[i] - self.r_grid_m or np.isnan(self.progress_at[i]):
                self.progress[i], self.progress_at[i] = remaining[i], t_s
            elif self.stall_timeout_s is not None and \
                    t_s - self.progress_at[i] > self.stall_timeout_s:  # fmt: skip
                self.drop(i, t_s, "stalled")
            elif (
                self.replan_stalled_s is not None
                and t_s - np.fmax(self.progress_at[i], self.replanned_at[i])
                >= self.replan_stalled_s - 1e-9
            ):
                self._replan_stalled(i, q[i], t_s)

    def _replan_stalled(self, i: int, q: np.ndarray, t_s: float) -> None:
        """A stalled prime's path again from ``q`` (its old one may start behind it or
        pass a door it was pushed past); progress is then measured on the new path, the
        stall clock runs on (only progress resets it)."""
        self.replanned_at[i] = t_s
        new = self.plan(i, q)
        if new is None:
            return  # keep the old path; the watchdog drops the target if it stays stalled
        self.set_path(i, new)
        self.replans += 1
        self.progress[i] = new.length_m
        self.emit("replan", i, t_s=t_s, path_m=round(new.length_m, 3))

    def stalled_s(self, robot: int, t_s: float) -> float:
        """Time the prime ``robot`` has not shrunk its path by ``Rgrid`` (0: not a prime)."""
        if self.role[robot] != PRIME or np.isnan(self.progress_at[robot]):
            return 0.0
        return t_s - float(self.progress_at[robot])

    def _secondary(self, i: int, q: np.ndarray, dist: float, off_path: float, t_s: float) -> None:
        if self._paths[i] is not None and off_path > self.r_gamma_m:
            new = self.plan(i, q)  # line 18: dragged too far from the path
            self.replans += 1
            if new is None:
                self.drop(i, t_s, "unreachable")
                self.set_role(i, CONNECTOR, t_s)
                return
            self.set_path(i, new)
            self.emit("replan", i, t_s=t_s, path_m=round(new.length_m, 3))
        if dist < self.rz_m:  # lines 19-21
            self.set_path(i, None)
            self.inside_since[i] = t_s
            self.set_role(i, ANCHOR, t_s)

    def abdicate(self, host: int, t_s: float) -> None:
        """The prime traveler decided its succession: anchor if it has a target, else connector."""
        if self.role[host] != PRIME:
            return
        self.set_role(host, ANCHOR if self.target[host] is not None else CONNECTOR, t_s)

    def anchored(self) -> np.ndarray:
        """Robots held at their target by ``f_anchor``: anchors, and a prime awaiting succession."""
        holding = (self.role == ANCHOR) | ((self.role == PRIME) & ~np.isnan(self.inside_since))
        return holding & self._has_target

    def done(self) -> bool:
        """No target left anywhere: every queue empty, nobody traveling or anchored."""
        return self.book.pending() == 0 and all(z is None for z in self.target)

    def targets_of(self, robots: np.ndarray) -> np.ndarray:
        return self._goal_m[np.asarray(robots, dtype=np.intp)].reshape(len(robots), -1)

    def summary(self) -> dict[str, Any]:
        return {
            "targets_total": self.book.total,
            "targets_reached": self.reached,
            "targets_dropped": self.dropped,
            "targets_pending": self.book.pending() + int(self._has_target.sum()),
            "replans": self.replans,
        }
