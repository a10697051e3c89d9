"""Effects of ``connectivity`` and ``multi_target`` parameters: a failed robot, a stalled
prime's replanning. The others are in ``test_parameter_effects_{table2, robot, estimator,
external, travel, roles, help, targets}.py``.
"""

from __future__ import annotations

import numpy as np

from _parameter_runs import changed, ran
from _parameters import effect
from tether.config import load_scenario
from tether.continuous.exploration.roles import PRIME, RolePlanner
from tether.continuous.exploration.targets import TargetBook
from tether.world.world import World


@effect("connectivity:estimator.failures")
def test_a_failed_robot_stops_and_exerts_no_force() -> None:
    data = load_scenario("connectivity_empty").model_dump(mode="json")
    data = changed(data, output__figures=False)
    data["strategy"]["params"].update(
        eigensolver="estimator",
        external={"kind": "random", "magnitude_n": 3.0, "hold_s": 1.0},
        estimator={"warmup_rounds": 300},
    )
    moved = {}
    for failures in ({}, {3: 5}):
        data["strategy"]["params"]["estimator"]["failures"] = failures
        r = ran(data, max_steps=20)
        moved[len(failures)] = np.linalg.norm(r.positions[-1] - r.positions[0], axis=1)
    assert moved[0].min() > 0.1  # pulled, every robot moves
    assert moved[1][3] == 0.0 and np.delete(moved[1], 3).min() > 0.1


@effect("multi_target:replan_stalled_s")
def test_a_stalled_prime_replans_and_progress_counts_on_the_new_path() -> None:
    """After a replan the progress baseline is the new path's length: moving 1 m along
    a longer new path is progress (the stall clock restarts), not a continued stall."""
    events: list[tuple] = []
    book = TargetBook.empty(1)
    book.add(0, [20.0, 0.0])
    planner = RolePlanner(
        World(dim=2), book, r_grid_m=0.75, inflate_m=1.0, rz_m=1.8, r_gamma_m=1.8,
        stall_timeout_s=60.0, emit=lambda *a, **k: events.append((a, k)), replan_stalled_s=5.0,
    )  # fmt: skip
    planner.start_up(np.zeros((1, 2)))
    planner.set_role(0, PRIME, 0.0)
    planner.update(np.zeros((1, 2)), 0.0)
    pushed = np.array([[0.0, 8.0]])  # pushed aside: the old path no longer shrinks
    for t in (1.0, 3.0, 4.9):
        planner.update(pushed, t)
    assert planner.replans == 0 and planner.stalled_s(0, 4.9) == 4.9
    planner.update(pushed, 5.0)
    assert planner.replans == 1 and events[-1][0][0] == "replan"
    new_length = planner.path[0].length_m
    assert new_length > 21.0  # from (0, 8): longer than the first path's 20 m
    ahead = pushed + np.array([[20.0, -8.0]]) / np.hypot(20.0, 8.0)  # 1 m along the new path
    planner.update(ahead, 6.0)
    assert planner.stalled_s(0, 6.0) == 0.0
    planner.update(ahead, 10.9)  # 4.9 s later, no replan yet: the clock restarted at 6 s
    assert planner.replans == 1


@effect("multi_target:replan_stalled_s")
def test_without_replan_stalled_s_a_stalled_prime_never_replans() -> None:
    book = TargetBook.empty(1)
    book.add(0, [20.0, 0.0])
    planner = RolePlanner(
        World(dim=2), book, r_grid_m=0.75, inflate_m=1.0, rz_m=1.8, r_gamma_m=1.8,
        stall_timeout_s=60.0, emit=lambda *a, **k: None, replan_stalled_s=None,
    )  # fmt: skip
    planner.start_up(np.zeros((1, 2)))
    planner.set_role(0, PRIME, 0.0)
    for t in np.arange(0.0, 30.0, 1.0):
        planner.update(np.array([[0.0, 8.0]]), float(t))
    assert planner.replans == 0 and planner.stalled_s(0, 29.0) == 29.0
