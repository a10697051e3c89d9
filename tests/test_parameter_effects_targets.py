"""``multi_target``'s target generators (``strategy.params.targets``: ``kind`` and its
``params``; :mod:`tether.continuous.exploration.targets`), set from a scenario: the queues the
strategy ``build`` made, and short runs for stay and expiry times."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from _continuous_runs import run, scenario, started
from _parameter_runs import built
from _parameters import effect
from tether.errors import ScenarioError

KEYS = ("multi_target:targets.kind", "multi_target:targets.params")


def with_targets(kind: str, seed: int = 0, n: int = 4, world: dict | None = None,
                 **params: Any) -> dict[str, Any]:  # fmt: skip
    """The row (or ``n`` robots in a row) with the generator ``kind`` and its params."""
    data = scenario("multi_target", targets={"kind": kind, "params": params})
    data["seed"] = seed
    data["team"] = {
        "n_robots": n,
        "init": {"kind": "positions", "positions": [[3.0 * k, 0.0, 5.0] for k in range(n)]},
    }
    if world is not None:
        data["world"] = world
    return data


def queues(data: dict[str, Any]) -> list[list[tuple]]:
    """Each robot's queue as ``(position, stay_s, appear_s, timeout_s)``."""
    book = built(data).strategy.targets
    return [[(z.position_m.tolist(), z.stay_s, z.appear_s, z.timeout_s) for z in q]
            for q in book.queues]  # fmt: skip


#: a 30 m x 30 m x 8 m box around the row (paper_random draws in a world's free grid)
BOX = {"scene": "empty", "dim": 3,
       "params": {"size_m": [30.0, 30.0], "height_m": 8.0, "resolution_m": 0.5}}  # fmt: skip


@effect(*KEYS)
def test_the_kind_picks_the_generator_that_fills_the_queues() -> None:
    fixed = queues(with_targets("fixed", queues=[{"robot": 2, "targets": [[1, 2, 3], [4, 5, 6]],
                                                  "stay_s": 2.0}]))  # fmt: skip
    assert fixed == [[], [], [([1, 2, 3], 2.0, 0.0, None), ([4, 5, 6], 2.0, 0.0, None)], []]
    drawn = queues(with_targets("paper_random", world=BOX, explorers=[2, 1]))
    assert [len(q) for q in drawn] == [2, 1, 0, 0]
    timed = queues(with_targets("schedule", targets=[{"robot": 1, "position_m": [7, 8, 4],
                                                      "at_s": 4.5}]))  # fmt: skip
    assert timed == [[], [([7, 8, 4], 3.0, 4.5, None)], [], []]
    with pytest.raises(ScenarioError, match="targets.kind: unknown target generator"):
        built(with_targets("fixd"))


@effect(*KEYS)
def test_paper_random_targets_follow_the_configuration_seed_alone() -> None:
    """Sec. 4.1: configuration k is the same for every team size and run seed."""

    def drawn(config_seed: int | None, seed: int = 0, n: int = 4) -> np.ndarray:
        params: dict[str, Any] = {"explorers": [3, 2]}
        if config_seed is not None:
            params["config_seed"] = config_seed
        q = queues(with_targets("paper_random", seed=seed, n=n, world=BOX, **params))
        return np.array([z[0] for queue in q for z in queue])

    a = drawn(5)
    np.testing.assert_array_equal(a, drawn(5, seed=9, n=6))
    assert not np.allclose(a, drawn(6))
    np.testing.assert_array_equal(drawn(None, seed=5), a)  # unset: the run seed is the config


@effect(*KEYS)
def test_paper_random_heights_clearance_and_stay(tmp_path: Path) -> None:
    z = np.array([t[0][2] for q in queues(with_targets("paper_random", world=BOX,
                                                        explorers=[10, 10], height_m=[6.0, 7.0]))
                  for t in q])  # fmt: skip
    assert z.min() >= 6.0 and z.max() <= 7.0
    path = tmp_path / "pillar.csv"  # a pillar of points at the box's middle, x = y = 15 m
    np.savetxt(path, [[15.0, 15.0, h] for h in np.arange(0.0, 8.01, 0.25)], delimiter=",")
    pillar = {"scene": "user_points", "dim": 3,
              "params": {"path": str(path), "bounds_m": [[0, 0, 0], [30, 30, 8]],
                         "resolution_m": 0.5}}  # fmt: skip
    for clearance in (1.0, 8.0):
        q = queues(with_targets("paper_random", world=pillar, explorers=[20, 20],
                                clearance_m=clearance, stay_s=7.0))  # fmt: skip
        xy = np.array([t[0][:2] for queue in q for t in queue])
        near = float(np.linalg.norm(xy - [15.0, 15.0], axis=1).min())
        assert near >= clearance - 0.5 and {t[1] for queue in q for t in queue} == {7.0}
        if clearance == 1.0:
            assert near < 8.0  # without the wider clearance some fall nearer


def anchored_and_released(stay_s: float) -> tuple[float, float]:
    """Robot 3's target 1 m ahead (within Rz): when it anchors (at once) and when the
    target is reached (its stay done)."""
    data = scenario("multi_target")
    data["strategy"]["params"]["targets"]["params"]["queues"] = [
        {"robot": 3, "targets": [[10.0, 0.0, 5.0]], "stay_s": stay_s}
    ]
    events = run(data, 60).recorder.events
    anchored = next(e["t_s"] for e in events if e["kind"] == "role" and e["new"] == "anchor")
    reached = next(e["t_s"] for e in events if e["kind"] == "target_reached")
    return anchored, reached


@effect(*KEYS)
def test_a_fixed_target_is_done_after_its_stay() -> None:
    for stay_s in (1.0, 3.0):
        anchored, reached = anchored_and_released(stay_s)
        assert reached - anchored == pytest.approx(stay_s, abs=0.11)


@effect(*KEYS)
def test_a_target_not_done_within_timeout_is_dropped_as_expired() -> None:
    for timeout_s, dropped in ((2.0, 1), (30.0, 0)):
        data = with_targets("fixed", queues=[{"robot": 3, "targets": [[49.0, 0.0, 5.0]]}],
                            timeout_s=timeout_s)  # fmt: skip
        r = run(data, 40)
        drops = [e for e in r.recorder.events if e["kind"] == "target_dropped"]
        assert [e["reason"] for e in drops] == ["expired"] * dropped
        if dropped:
            assert drops[0]["t_s"] == pytest.approx(2.0, abs=0.11)


@effect(*KEYS)
def test_a_scheduled_target_is_taken_when_it_appears() -> None:
    for at_s in (0.0, 2.0):
        data = with_targets("schedule", targets=[{"robot": 3, "position_m": [20.0, 0.0, 5.0],
                                                  "at_s": at_s}])  # fmt: skip
        s, _ = started(data)
        assert (s.planner.target[3] is None) == (at_s > 0)  # not there at start-up
        taken = [e for e in run(data, 30).recorder.events if e["kind"] == "target_taken"]
        assert taken[0]["t_s"] == pytest.approx(at_s, abs=0.11)
