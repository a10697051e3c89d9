"""Algorithm 1 in ``multi_target``: planning (``r_grid_m``, ``inflate_m``), replanning
(``r_gamma_m``), the election (``election_criterion``, ``messages``), where the team
starts (``start``); ``docs/multi_target.md``. Set from a scenario; most checks need only
the strategy ``build`` made, reset (the start-up plans every robot's first path)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from _continuous_runs import columns, run, scenario, started
from _parameters import effect
from tether.continuous.exploration.roles import PRIME, SECONDARY


def door_world(tmp_path: Path) -> dict[str, Any]:
    """A 20 m x 20 m box split by a wall at x = 10 m with a 2 m door (y 9-11 m); 0.25 m
    cells, so the planning cells of 0.25 m have centres 1.0 m from both door posts."""
    path = tmp_path / "door.csv"
    ys = np.r_[np.arange(0.0, 9.01, 0.2), np.arange(11.0, 20.01, 0.2)]
    np.savetxt(path, np.column_stack([np.full(len(ys), 10.0), ys]), delimiter=",")
    return {
        "scene": "user_points",
        "dim": 2,
        "params": {"path": str(path), "bounds_m": [[0, 0], [20, 20]], "resolution_m": 0.25},
    }


def in_the_door_world(tmp_path: Path, queues: list[dict], **params: Any) -> dict[str, Any]:
    """The row along x = 6 m, left of the wall, with the target ``queues`` given."""
    data = scenario("multi_target", **params)
    data["world"] = door_world(tmp_path)
    data["team"]["init"]["positions"] = [[6, 4], [6, 7], [6, 10], [6, 13]]
    data["strategy"]["params"]["targets"]["params"]["queues"] = queues
    return data


#: robot 2 (at (6, 10)) goes to (14, 10): 8 m, straight through the door
THROUGH = [{"robot": 2, "targets": [[14.0, 10.0]], "stay_s": 1.0}]


def planned(tmp_path: Path, **params: Any):  # noqa: ANN201
    """Robot 2's planned path through the door, or None (the target dropped)."""
    s, _ = started(in_the_door_world(tmp_path, THROUGH, **params))
    assert s.planner.dropped == (s.planner.path[2] is None)
    return s.planner.path[2]


@effect("multi_target:r_grid_m")
def test_r_grid_is_the_planning_cell_and_the_progress_a_prime_must_make(tmp_path) -> None:
    """A* plans on cells of ``Rgrid`` (a 20 m box: 80 cells of 0.25 m, 16 of 1.25 m a
    side); a prime that has not shrunk its remaining path by ``Rgrid`` for
    ``stall_timeout_s`` drops its target: crawling 1 m per 10 s is progress for cells of
    0.75 m and a stall for cells of 1 m (with an 8 s timeout)."""
    for cell, side in ((0.25, 80), (1.25, 16)):
        s, _ = started(in_the_door_world(tmp_path, THROUGH, r_grid_m=cell, inflate_m=0.9))
        assert s.planner._planning.resolution_m == cell
        assert s.planner._planning.occupied.shape == (side, side)
    for cell, dropped in ((0.75, 0), (1.0, 1)):
        s, q = started(scenario("multi_target", r_grid_m=cell, stall_timeout_s=8.0))
        s.planner.set_role(3, PRIME, 0.0)
        for t in np.arange(0.0, 40.0, 0.5):
            crawl = q.copy()
            crawl[3, 0] += 0.1 * t
            s.planner.update(crawl, float(t))
        assert s.planner.dropped == dropped, cell


@effect("multi_target:inflate_m")
def test_a_larger_inflation_keeps_the_path_farther_from_the_walls(tmp_path) -> None:
    """Robot 0 (at (6, 4)) to (14, 4): around the door's lower post at (10, 9)."""
    queues = [{"robot": 0, "targets": [[14.0, 4.0]], "stay_s": 1.0}]
    post = np.array([10.0, 9.0])
    clearance = {}
    for inflate in (0.5, 0.9):
        s, _ = started(in_the_door_world(tmp_path, queues, r_grid_m=0.25, inflate_m=inflate))
        points = s.planner.path[0].points
        clearance[inflate] = float(np.linalg.norm(points - post, axis=1).min())
    assert clearance[0.9] > clearance[0.5] + 0.2
    assert clearance[0.5] > 0.5 - 0.2  # inflation less the smoothing's corner cut


@effect("multi_target:r_gamma_m")
def test_a_secondary_dragged_farther_than_r_gamma_from_its_path_plans_again() -> None:
    for r_gamma, replans in ((1.0, 1), (3.0, 0)):
        s, q = started(scenario("multi_target", r_gamma_m=r_gamma))
        assert s.planner.role[3] == SECONDARY and s.planner.replans == 0
        dragged = q.copy()
        dragged[3, 1] += 2.0  # 2 m off its path along +x
        s.planner.update(dragged, 0.1)
        assert s.planner.replans == replans, r_gamma
        if replans:  # the new path starts where the robot is
            np.testing.assert_allclose(s.planner.path[3].points[0], dragged[3], atol=0.5)
    assert started(scenario("multi_target", rz_m=1.2))[0].planner.r_gamma_m == 1.2  # Rz


# -- the election -----------------------------------------------------------------------------


@effect("multi_target:election_criterion")
def test_the_criterion_elects_the_shortest_path_or_the_nearest_target(tmp_path) -> None:
    """Robot 0's target is 6 m away behind the wall (13.5 m through the door); robot 3's
    7.2 m away in the open: the remaining path elects robot 3, the distance robot 0."""
    queues = [{"robot": 0, "targets": [[12.0, 4.0]], "stay_s": 1.0},
              {"robot": 3, "targets": [[2.0, 19.0]], "stay_s": 1.0}]  # fmt: skip
    for criterion, winner in (("path_length", 3), ("distance", 0)):
        data = in_the_door_world(tmp_path, queues, election_criterion=criterion,
                                 r_grid_m=0.25, inflate_m=0.9)  # fmt: skip
        r = run(data, 12)
        elected = [e for e in r.recorder.events if e["kind"] == "election"]
        assert elected[0]["candidates"] == [0, 3] and elected[0]["winner"] == winner, criterion


def first_prime_step(**params: Any) -> int:
    prime = columns(run(scenario("multi_target", **params), 40))["prime"]
    elected = np.flatnonzero(prime >= 0)
    assert len(elected), f"no prime elected in 40 steps with {params}"
    return int(elected[0])


@effect("multi_target:messages.rounds_per_step")
def test_more_message_rounds_per_step_elect_the_first_prime_sooner() -> None:
    """The start-up election floods for 2 (N - 1) = 6 rounds, its result up to N - 1."""
    one = first_prime_step()
    assert 6 <= one <= 10
    assert first_prime_step(messages={"rounds_per_step": 10}) <= 1


@effect("multi_target:messages.delay_rounds")
def test_delayed_messages_elect_the_first_prime_later_but_elect_it() -> None:
    """Every hop takes 1 + delay rounds; the only candidate, robot 3, is 3 hops from the
    host (robot 0): the election's round trip grows by 6 rounds per round of delay."""
    steps = [first_prime_step(messages={"delay_rounds": d}) for d in (0, 1, 2)]
    assert steps[0] + 6 <= steps[1] and steps[1] + 6 <= steps[2] < 40, steps


@effect("multi_target:messages.loss_probability")
def test_election_consensus_and_help_messages_are_lost_with_the_loss_probability() -> None:
    s, _ = started(scenario("multi_target", messages={"loss_probability": 0.4}))
    layers = (s.election.layer, s.consensus.layer, s.help.layer)
    assert all(layer.params.loss_probability == 0.4 for layer in layers)
    for p in (0.0, 0.4):
        s = run(scenario("multi_target", messages={"loss_probability": p}), 60).built.strategy
        sent = s.election.layer.sent + s.consensus.layer.sent
        delivered = s.election.layer.delivered + s.consensus.layer.delivered
        assert sent > 500 and delivered / sent == pytest.approx(1 - p, abs=0.06)  # 3 sigma


# -- where the team starts --------------------------------------------------------------------


def start_team(seed: int = 0, **start: Any) -> np.ndarray:
    """The team placed by ``start`` (``team.init`` not ``positions``) in a 20 x 20 x 8 m box."""
    data = scenario("multi_target", start=start)
    data["seed"] = seed
    data["world"] = {
        "scene": "empty",
        "dim": 3,
        "params": {"size_m": [20.0, 20.0], "height_m": 8.0, "resolution_m": 0.5},
    }
    data["team"]["init"] = {"kind": "random_connected"}
    data["strategy"]["params"]["targets"]["params"]["queues"][0]["targets"] = [[15, 15, 4]]
    return started(data)[1]


@effect("multi_target:start.center_m")
def test_the_team_grows_from_center() -> None:
    for center in ([5.0, 6.0, 3.0], [14.0, 12.0, 5.0]):
        q = start_team(center_m=center)
        np.testing.assert_array_equal(q[0], center)
        assert np.linalg.norm(q - center, axis=1).max() < 4 * 2.5  # R's = 2.5 m per robot


@effect("multi_target:start.height_m")
def test_the_first_robot_starts_in_the_height_range() -> None:
    for low, high in ((1.0, 1.5), (6.0, 6.5)):
        z = [start_team(seed, height_m=[low, high])[0, 2] for seed in range(4)]
        assert all(low <= h <= high for h in z), z


@effect("multi_target:start.margin_m")
def test_the_first_robot_starts_margin_inside_the_bounds() -> None:
    firsts = np.array([start_team(seed, margin_m=8.0)[0, :2] for seed in range(6)])
    assert firsts.min() >= 8.0 and firsts.max() <= 12.0
    loose = np.array([start_team(seed, margin_m=1.0)[0, :2] for seed in range(6)])
    assert loose.min() < 8.0 or loose.max() > 12.0
