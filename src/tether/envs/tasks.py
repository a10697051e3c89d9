"""What a team is asked to do in an environment, per scenario kind: its progress and its end.

Each task measures progress from the robots' positions alone, so a learned policy and a
scripted one are scored by the same rule:

* :class:`LeaderPath` (``silent``): the leader's progress along its path, as the
  strategy measures it (the closest path point within two sensing ranges ahead of the
  progress so far, never backwards); done when the leader is within the path's
  ``goal_tolerance_m`` of its end, as the strategy's run ends.
* :class:`Goals` (``connectivity`` with ``external.kind: goal``): metres the goal robots
  came closer to their goals; never done (the run goes to ``sim.max_steps``).
* :class:`Targets` (``multi_target``): each robot's queue of targets in order; a target
  is completed after its robot spent ``stay_s`` within ``rz_m`` of it (consecutively);
  progress is the metres robots came closer to their current targets; done when every
  queue is empty.
* :class:`Coverage` (``recurrent``, ``utility``): the percentage of the map's free cells
  (cells of ``coverage_cell_m``) seen: within ``sensing.range_m`` of a robot with a clear
  line of sight; never done.
* :class:`NoTask`: no progress (connectivity and safety terms only).

``offsets(q)`` is each robot's task vector (to its leader carrot, goal, target or the
base station) and a flag saying whether it has one: part of the observation.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from tether.paths.trajectory import Polyline
from tether.world.world import World


class NoTask:
    """No task: no progress, never done."""

    def reset(self, q: np.ndarray) -> None:
        self.n, self.dim = q.shape

    def update(self, q_old: np.ndarray, q: np.ndarray, t_s: float) -> tuple[float, int]:
        """Progress and targets completed by the move ``q_old -> q`` ending at ``t_s``."""
        return 0.0, 0

    def offsets(self, q: np.ndarray, t_s: float) -> tuple[np.ndarray, np.ndarray]:
        return np.zeros_like(q), np.zeros(len(q))

    def done(self) -> bool:
        return False

    def metrics(self) -> dict[str, Any]:
        return {}


class LeaderPath(NoTask):
    """The leader follows its path (``trajectory``: a :class:`Polyline` or a function of time)."""

    def __init__(
        self,
        leader: int,
        trajectory: Any,
        speed_mps: float,
        dt_s: float,
        window_m: float,
        goal_tolerance_m: float,
    ) -> None:
        self.leader = leader
        self.trajectory = trajectory
        self.carrot_m = speed_mps * dt_s
        self.dt_s = dt_s
        self.window_m = window_m
        self.goal_tolerance_m = goal_tolerance_m

    def reset(self, q: np.ndarray) -> None:
        super().reset(q)
        self.progress_m = 0.0
        self._done = False

    def update(self, q_old: np.ndarray, q: np.ndarray, t_s: float) -> tuple[float, int]:
        traj = self.trajectory
        if not isinstance(traj, Polyline):
            return 0.0, 0
        before = self.progress_m
        s = traj.project(q[self.leader], self.progress_m, window_m=self.window_m)
        self.progress_m = max(self.progress_m, s)
        self._done = bool(np.linalg.norm(q[self.leader] - traj.end) <= self.goal_tolerance_m)
        return self.progress_m - before, 0

    def offsets(self, q: np.ndarray, t_s: float) -> tuple[np.ndarray, np.ndarray]:
        out, flag = np.zeros_like(q), np.zeros(len(q))
        traj = self.trajectory
        if isinstance(traj, Polyline):
            point = traj.at(self.progress_m + self.carrot_m)
        else:
            point = np.asarray(traj(t_s + self.dt_s), dtype=float)
        out[self.leader] = point - q[self.leader]
        flag[self.leader] = 1.0
        return out, flag

    def done(self) -> bool:
        return self._done

    def metrics(self) -> dict[str, Any]:
        if not isinstance(self.trajectory, Polyline):
            return {}
        length = self.trajectory.length_m
        return {"task_path_progress": self.progress_m / max(length, 1e-12)}


class Goals(NoTask):
    """``robots`` head for ``goals`` (the operator goals of a ``connectivity`` scenario)."""

    def __init__(self, robots: list[int], goals: np.ndarray) -> None:
        self.robots = np.asarray(robots, dtype=int)
        self.goals = np.asarray(goals, dtype=float).reshape(len(self.robots), -1)

    def _distances(self, q: np.ndarray) -> np.ndarray:
        return np.linalg.norm(self.goals - q[self.robots], axis=1)

    def reset(self, q: np.ndarray) -> None:
        super().reset(q)
        self.start_m = self._distances(q)
        self.last_m = self.start_m.copy()

    def update(self, q_old: np.ndarray, q: np.ndarray, t_s: float) -> tuple[float, int]:
        now = self._distances(q)
        gain = float((self.last_m - now).sum())
        self.last_m = now
        return gain, 0

    def offsets(self, q: np.ndarray, t_s: float) -> tuple[np.ndarray, np.ndarray]:
        out, flag = np.zeros_like(q), np.zeros(len(q))
        out[self.robots] = self.goals - q[self.robots]
        flag[self.robots] = 1.0
        return out, flag

    def metrics(self) -> dict[str, Any]:
        return {
            "task_goal_distance_m": float(self.last_m.sum()),
            "task_goal_distance_start_m": float(self.start_m.sum()),
        }


class Targets(NoTask):
    """Each robot visits its queue of targets in order (``multi_target``'s targets).

    ``queues[r]`` lists ``(position_m, stay_s, appear_s)`` of robot ``r``'s targets.
    """

    def __init__(
        self, queues: list[list[tuple[np.ndarray, float, float]]], rz_m: float, dt_s: float
    ) -> None:
        self.queues = queues
        self.rz_m = rz_m
        self.dt_s = dt_s
        self.total = sum(len(queue) for queue in queues)

    def reset(self, q: np.ndarray) -> None:
        super().reset(q)
        self.next = np.zeros(len(self.queues), dtype=int)
        self.stayed_s = np.zeros(len(self.queues))
        self.completed = 0
        self.completion_s: float | None = None

    def _current(self, robot: int, t_s: float) -> np.ndarray | None:
        queue, k = self.queues[robot], self.next[robot]
        if k < len(queue) and queue[k][2] <= t_s + 1e-12:
            return queue[k][0]
        return None

    def update(self, q_old: np.ndarray, q: np.ndarray, t_s: float) -> tuple[float, int]:
        gain, done_now = 0.0, 0
        for robot in range(len(self.queues)):
            target = self._current(robot, t_s - self.dt_s)
            if target is None:
                continue
            near = float(np.linalg.norm(target - q[robot]))
            gain += float(np.linalg.norm(target - q_old[robot])) - near
            self.stayed_s[robot] = self.stayed_s[robot] + self.dt_s if near <= self.rz_m else 0.0
            if self.stayed_s[robot] >= self.queues[robot][self.next[robot]][1] - 1e-9:
                self.next[robot] += 1
                self.stayed_s[robot] = 0.0
                done_now += 1
        self.completed += done_now
        if self.completion_s is None and self.done():
            self.completion_s = t_s
        return gain, done_now

    def offsets(self, q: np.ndarray, t_s: float) -> tuple[np.ndarray, np.ndarray]:
        out, flag = np.zeros_like(q), np.zeros(len(q))
        for robot in range(len(self.queues)):
            target = self._current(robot, t_s)
            if target is not None:
                out[robot] = target - q[robot]
                flag[robot] = 1.0
        return out, flag

    def done(self) -> bool:
        return self.completed >= self.total

    def metrics(self) -> dict[str, Any]:
        return {
            "task_targets_completed": self.completed,
            "task_targets_total": self.total,
            "task_completion_time_s": self.completion_s,
        }


class Coverage(NoTask):
    """The map seen by the robots, in cells of ``cell_m``, from the base station ``base``."""

    def __init__(self, world: World, range_m: float, cell_m: float, base: np.ndarray) -> None:
        if world.bounds_m is None:
            raise ValueError("coverage needs a world with bounds (a map)")
        self.world = world
        self.range_m = range_m
        self.base = np.asarray(base, dtype=float).reshape(-1)
        lo, hi = world.bounds_m
        shape = np.maximum(np.floor((hi - lo) / cell_m).astype(int), 1)
        axes = [lo[d] + (np.arange(shape[d]) + 0.5) * cell_m for d in range(world.dim)]
        self.centres = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, world.dim)
        self.free = world.points_free(self.centres)
        self.cell_m = cell_m

    def reset(self, q: np.ndarray) -> None:
        super().reset(q)
        self.seen = np.zeros(len(self.centres), dtype=bool)
        self._look(q)

    def fraction(self) -> float:
        return float(self.seen[self.free].sum()) / max(int(self.free.sum()), 1)

    def _look(self, q: np.ndarray) -> None:
        for robot in range(len(q)):
            d = np.linalg.norm(self.centres - q[robot], axis=1)
            idx = np.flatnonzero((d <= self.range_m) & self.free & ~self.seen)
            if len(idx):
                a = np.broadcast_to(q[robot], (len(idx), q.shape[1]))
                idx = idx[self.world.segments_clear(a, self.centres[idx])]
                self.seen[idx] = True

    def update(self, q_old: np.ndarray, q: np.ndarray, t_s: float) -> tuple[float, int]:
        before = self.fraction()
        self._look(q)
        return 100.0 * (self.fraction() - before), 0

    def offsets(self, q: np.ndarray, t_s: float) -> tuple[np.ndarray, np.ndarray]:
        return self.base[None, :] - q, np.ones(len(q))

    def metrics(self) -> dict[str, Any]:
        return {"task_explored_fraction": self.fraction()}
