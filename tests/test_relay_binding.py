"""Relay binding (Sec. VI): the paper's rule (P_f of frontiers and fake frontiers) and ours.

A hand-made plan on a graph of six vertices, the P_f worked out by hand::

    f(2) - a(1) - BS(0) - c(3) - k(4)        0 - e(5)

robots: r0 -> a (relay, arrives at t = 5), r1 -> f (frontier, t = 10),
r2 -> c (relay, t = 3), r3 -> k (fake frontier, t = 2), r4 -> e (relay, t = 1),
r5 -> b(6) (relay, t = 1) with b linked only to d(7) (relay of r6, t = 4), d to BS.
"""

from __future__ import annotations

import numpy as np
import pytest

from tether.recurrent.planning import readiness
from tether.recurrent.planning.readiness import ReadinessTracker, binding_targets, relay_paths

EDGES = np.array([[0, 1], [1, 2], [0, 3], [3, 4], [0, 5], [6, 7], [7, 0]])
GOALS = {0: 1, 1: 2, 2: 3, 3: 4, 4: 5, 5: 6, 6: 7}
TIMES = {0: 5.0, 1: 10.0, 2: 3.0, 3: 2.0, 4: 1.0, 5: 1.0, 6: 4.0}
FRONTIER_LIKE = {2, 4}  # f (frontier) and k (fake frontier)


def test_targets_of_the_two_rules() -> None:
    assert binding_targets(GOALS, FRONTIER_LIKE, "frontiers") == [1, 3]
    assert binding_targets(GOALS, FRONTIER_LIKE, "assigned") == list(GOALS)
    with pytest.raises(ValueError):
        binding_targets(GOALS, FRONTIER_LIKE, "all")


def test_paper_rule_paths_by_hand() -> None:
    paths = relay_paths(GOALS, TIMES, binding_targets(GOALS, FRONTIER_LIKE, "frontiers"), EDGES)
    # P_f: f's robot arrives last (t = 10); by then a is occupied: f - a - BS
    # P_k: at t = 2 (k's arrival) c is empty; at t = 3 (c's arrival) k - c - BS forms
    assert paths == {1: [1, 0], 3: [3, 2]}


def test_assigned_rule_also_binds_relays_by_hand() -> None:
    paths = relay_paths(GOALS, TIMES, binding_targets(GOALS, FRONTIER_LIKE, "assigned"), EDGES)
    assert paths[1] == [1, 0] and paths[3] == [3, 2]
    # relays linked to the BS directly hold only themselves
    assert paths[0] == [0] and paths[2] == [2] and paths[4] == [4] and paths[6] == [6]
    # b (t = 1) links to the BS only once d's robot arrives (t = 4): b - d - BS
    assert paths[5] == [5, 6]


def _tracker(rule: str) -> ReadinessTracker:
    tracker = ReadinessTracker()
    targets = binding_targets(GOALS, FRONTIER_LIKE, rule)
    for f, members in relay_paths(GOALS, TIMES, targets, EDGES).items():
        tracker.add(GOALS[f], [GOALS[m] for m in members])
    return tracker


def test_readiness_at_t4_differs_only_for_the_relay_chain() -> None:
    """At t = 4 robots r2..r6 are at their goals and r0, r1 under way.

    Paper's rule: d's robot (r6) is bound by nothing and ready; when the BS re-plans
    it away, b's robot (r5) loses its only link for good. Ours binds r6 until b's
    data reached the BS (r5 delivered).
    """
    keys = np.array([GOALS[r] for r in range(7)])
    at_goal = np.array([False, False, True, True, True, True, True])
    delivered = np.array([False, False, True, False, True, False, True])  # r5 not yet
    connected = np.ones(7, dtype=bool)
    done = at_goal.copy()
    ready = {}
    for rule in ("frontiers", "assigned"):
        tracker = _tracker(rule)
        tracker.update(keys, at_goal, delivered)
        ready[rule] = set(np.flatnonzero(tracker.ready(done, connected, keys)).tolist())
    # k's data (r3) is not at the BS yet: k and c (r2) are held under both rules
    assert ready["frontiers"] == {4, 5, 6}
    assert ready["assigned"] == {4}
    # once b's data is at the BS, r5 and r6 are released by our rule too
    delivered[5] = True
    tracker = _tracker("assigned")
    tracker.update(keys, at_goal, delivered)
    assert set(np.flatnonzero(tracker.ready(done, connected, keys)).tolist()) == {4, 5, 6}


def test_branch_is_closed_under_shared_relays() -> None:
    """Preempting a relay shared by two P_f breaks both: both branches are preempted."""
    tracker = ReadinessTracker()
    tracker.add(10, [11])  # P of the robot at 10 runs through 11
    tracker.add(12, [11, 13])  # so does the one at 12 (and through 13)
    tracker.add(20, [21])  # another branch
    keys = np.array([10, 11, 12, 13, 20, 21])
    assert tracker.branch(0, keys) == {0, 1, 2, 3}
    assert tracker.branch(3, keys) == {0, 1, 2, 3}
    assert tracker.branch(5, keys) == {4, 5}


@pytest.mark.parametrize("seed", range(20))
def test_paths_on_the_goals_edges_equal_paths_on_all_edges(
    seed: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Only edges between goals and the BS are searched: the same ``P_f`` as on every
    edge (the reference), whichever of several shortest paths the order of each
    vertex's neighbours picks."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(8, 60))
    edges = np.array([(a, b) for a in range(n) for b in range(a + 1, n) if rng.random() < 0.2])
    edges = edges.reshape(-1, 2)[rng.permutation(len(edges))]
    robots = int(rng.integers(2, min(12, n - 1)))
    vertices = rng.choice(np.arange(1, n), size=robots, replace=False).tolist()
    goals = dict(enumerate(vertices))
    times = {r: float(rng.integers(0, 6)) for r in goals}
    targets = [r for r in goals if rng.random() < 0.7]
    got = relay_paths(goals, times, targets, edges)
    with monkeypatch.context() as m:
        m.setattr(readiness, "_edges_between", lambda e, _v: np.asarray(e).reshape(-1, 2))
        want = relay_paths(goals, times, targets, edges)
    assert got == want
