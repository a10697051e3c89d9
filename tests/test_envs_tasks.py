"""The environments' tasks score what their documentation says, checked on hand-made moves.

Each task is fed positions chosen here and its progress, completions and end are
compared with values worked out by hand: a target needs ``stay_s`` *consecutive* seconds
within ``rz_m``; the leader's progress along its path never goes back; goal progress is
the metres the goal robots came closer.
"""

from __future__ import annotations

import numpy as np
import pytest

from tether.envs.tasks import Goals, LeaderPath, Targets
from tether.paths.trajectory import Polyline

DT_S = 1.0


def feed(task, positions: list[list[list[float]]]) -> list[tuple[float, int]]:  # noqa: ANN001
    """Reset ``task`` at the first positions, then move through the others."""
    q = np.asarray(positions, dtype=float)
    task.reset(q[0])
    return [task.update(q[k - 1], q[k], k * DT_S) for k in range(1, len(q))]


def test_a_target_needs_its_stay_in_one_visit() -> None:
    """stay 2 s within 1 m: in, out, in, in completes it at the fourth step, not the third."""
    task = Targets([[(np.array([10.0, 0.0]), 2.0, 0.0)]], rz_m=1.0, dt_s=DT_S)
    path = [[[0.0, 0.0]], [[10.0, 0.5]], [[13.0, 0.0]], [[10.0, 0.0]], [[9.5, 0.0]]]
    out = feed(task, path)
    assert [done for _, done in out] == [0, 0, 0, 1]
    assert task.done() and task.metrics()["task_completion_time_s"] == 4 * DT_S
    progress = [gain for gain, _ in out]  # metres closer to the target
    np.testing.assert_allclose(progress, [10 - 0.5, 0.5 - 3.0, 3.0, -0.5])


def test_targets_are_visited_in_their_order_and_appear_on_time() -> None:
    """The second target counts only after the first; the first appears at t = 2 s."""
    queue = [(np.array([5.0, 0.0]), 0.0, 2.0), (np.array([0.0, 5.0]), 0.0, 0.0)]
    task = Targets([queue], rz_m=0.5, dt_s=DT_S)
    out = feed(task, [[[0.0, 5.0]], [[0.0, 5.0]], [[5.0, 0.0]], [[5.0, 0.0]], [[0.0, 5.0]]])
    assert [done for _, done in out] == [0, 0, 1, 1]  # at (0, 5) first: not yet its turn
    assert task.metrics()["task_targets_completed"] == 2


def test_the_leader_s_progress_never_goes_back() -> None:
    """Progress is the closest path point within ``window_m`` ahead of the progress so far:
    a step back gains nothing, a jump gains at most the window; done at the end's tolerance."""
    path = Polyline(np.array([[0.0, 0.0], [20.0, 0.0]]))
    task = LeaderPath(0, path, speed_mps=1.0, dt_s=DT_S, window_m=10.0, goal_tolerance_m=0.5)
    out = feed(task, [[[0.0, 0.0]], [[4.0, 1.0]], [[2.0, 0.0]], [[6.0, 0.0]], [[19.6, 0.0]]])
    np.testing.assert_allclose([gain for gain, _ in out], [4.0, 0.0, 2.0, 10.0])
    assert task.done() and task.metrics()["task_path_progress"] == pytest.approx(16 / 20)


def test_goal_progress_is_the_metres_closer() -> None:
    task = Goals([0, 2], np.array([[10.0, 0.0], [0.0, 10.0]]))
    out = feed(task, [[[0, 0], [5, 5], [0, 0]], [[3, 0], [9, 9], [0, 4]], [[1, 0], [0, 0], [0, 4]]])
    np.testing.assert_allclose([gain for gain, _ in out], [3 + 4, -2 + 0])
    assert task.metrics()["task_goal_distance_m"] == pytest.approx(9 + 6)
