"""Robot readiness and the relay paths ``P_f`` (Sec. VI of the paper).

Recurrent-connectivity paper (Banfi et al., Sec. VI): for each frontier ``f``
of a plan (real or "fake", Sec. V), ``P_f`` is the first path between ``f``
and the BS in ``G^t`` that will be formed given the robots' travel times. It is
computed offline: order robots by increasing travel time; for each robot
``j`` restrict ``G^t`` to the BS and the goals of robots arriving no later
than ``j``; if ``f`` is connected to the BS there, ``P_f`` is the shortest
such path; otherwise try the next robot.

A robot ``j`` is *ready* when (a) it reached its goal (and finished its scan
if the goal is a frontier) and (b) for every ``f`` whose ``P_f`` holds ``j``'s
goal, ``f``'s data reached the BS and every robot on ``P_f`` is at its goal.
Ready robots are connected to the BS by definition (the BS must be able to
send them a plan), so readiness also requires a current link to the BS.

Which robots get a ``P_f`` is :func:`binding_targets`: the paper's rule (its
frontiers and fake frontiers) or, the planner's default, every robot the plan
sends somewhere (``docs/explanation/recurrent.md`` explains the deviation).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Obligation", "ReadinessTracker", "binding_targets", "relay_paths"]

#: which robots of a plan get a relay path ``P_f`` (see :func:`binding_targets`)
BINDINGS = ("assigned", "frontiers")


def _bfs_path(adj: dict[int, list[int]], allowed: set[int], src: int, dst: int) -> list[int] | None:
    if src not in allowed or dst not in allowed:
        return None
    prev = {src: src}
    q = deque([src])
    while q:
        u = q.popleft()
        if u == dst:
            path = [u]
            while path[-1] != src:
                path.append(prev[path[-1]])
            return path[::-1]
        for w in adj.get(u, ()):
            if w in allowed and w not in prev:
                prev[w] = u
                q.append(w)
    return None


def _edges_between(edges: np.ndarray, vertices: list[int]) -> np.ndarray:
    """The edges with both ends in ``vertices``, in their order.

    Every search of :func:`relay_paths` stays on the goals and the BS, so only those
    edges matter; kept in order, each vertex scans its neighbours as in the whole graph.
    """
    edges = np.asarray(edges, dtype=int).reshape(-1, 2)
    return edges[np.isin(edges, vertices).all(axis=1)]


def relay_paths(
    goals: dict[int, int],
    travel_times: dict[int, float],
    targets: list[int],
    edges: np.ndarray,
    base: int = 0,
) -> dict[int, list[int] | None]:
    """``P_f`` for every target robot, as the list of robots whose goals form it.

    Parameters
    ----------
    goals
        Robot id -> vertex of ``G^t`` it is headed to (or sits on); goals are distinct.
    travel_times
        Robot id -> expected time to reach (and finish at) its goal.
    targets
        Robots whose goal is a (real or fake) frontier of the plan.
    edges
        ``(E, 2)`` communication edges ``C^t`` between vertex ids.
    base
        The BS vertex.

    Returns
    -------
    dict
        Target robot -> robots on ``P_f`` from ``f`` to the BS (the target
        first), or ``None`` if no such path forms.
    """
    adj: dict[int, list[int]] = {}
    for a, b in _edges_between(edges, [base, *goals.values()]).tolist():
        adj.setdefault(a, []).append(b)
        adj.setdefault(b, []).append(a)
    owner = {v: r for r, v in goals.items()}
    order = sorted(goals, key=lambda r: (travel_times[r], r))
    out: dict[int, list[int] | None] = {}
    for f in targets:
        out[f] = None
        allowed = {base}
        for j in order:
            allowed.add(goals[j])
            if travel_times[j] < travel_times[f]:
                continue
            path = _bfs_path(adj, allowed, goals[f], base)
            if path is not None:
                out[f] = [owner[v] for v in path if v != base]
                break
    return out


def binding_targets(
    assignment: dict[int, int], frontier_like: set[int], rule: str = "assigned"
) -> list[int]:
    """Robots of a plan whose goal gets a relay path ``P_f``.

    ``assignment`` maps robots to the goal vertices of the deployment;
    ``frontier_like`` are the plan's frontiers and fake frontiers (Sec. V).

    ``"frontiers"`` is the paper's rule (Sec. VI): ``P_f`` for every frontier and
    fake frontier of the plan. ``"assigned"`` binds a ``P_f`` for every robot of
    the assignment: a relay is then also held until the chain linking its own goal
    to the BS has formed. Without it, a relay that arrives before the robots that
    would link it can be ready, re-planned and gone when they arrive, and they
    stand disconnected for good: the configuration of later plans treats the
    goals of non-ready robots as connected to the BS (Sec. IV-A), which only the
    ``P_f`` of their own plan guarantees.
    """
    if rule not in BINDINGS:
        raise ValueError(f"relay binding must be one of {BINDINGS} (got {rule!r})")
    if rule == "assigned":
        return list(assignment)
    return [r for r, v in assignment.items() if v in frontier_like]


@dataclass
class Obligation:
    """The robots on ``members`` relay until ``target``'s data is at the BS.

    Both are *locations* (stable vertex keys, e.g. coarse node ids) rather than
    robot ids, because a re-deployment may swap which robot heads where.
    """

    target: int
    members: frozenset[int]
    plan: int = -1


@dataclass
class ReadinessTracker:
    """Outstanding relay obligations and the readiness rule of Sec. VI.

    ``goal_keys[r]`` is the location key of robot ``r``'s goal.
    """

    obligations: list[Obligation] = field(default_factory=list)

    def add(self, target: int, members: list[int], plan: int = -1) -> None:
        """Bind the robots headed to ``members`` (``P_f``) to the frontier location ``target``."""
        self.obligations.append(Obligation(int(target), frozenset(members) | {int(target)}, plan))

    def branch(self, robot: int, goal_keys: np.ndarray) -> set[int]:
        """Robots of the branches ``robot`` belongs to (Sec. VII-B), transitively.

        The robots sharing an outstanding obligation with ``robot``; preempting
        them breaks every other obligation they hold too (a relay shared by two
        branches), so the robots of those join, until no obligation is left
        half-preempted.
        """
        locs = {int(goal_keys[robot])}
        grew = True
        while grew:
            grew = False
            for o in self.obligations:
                if o.members & locs and not o.members <= locs:
                    locs |= o.members
                    grew = True
        return {r for r in range(len(goal_keys)) if int(goal_keys[r]) in locs} | {robot}

    def drop(self, locations: set[int]) -> None:
        """Forget obligations touching any of ``locations`` (preempted branches)."""
        self.obligations = [o for o in self.obligations if not (o.members & locations)]

    def update(self, goal_keys: np.ndarray, at_goal: np.ndarray, delivered: np.ndarray) -> None:
        """Discharge obligations whose target's data arrived and whose members are at goal.

        An obligation whose target location no robot is headed to any more is
        void (its robot was preempted) and is dropped.
        """
        by_loc: dict[int, list[int]] = {}
        for r, k in enumerate(np.asarray(goal_keys).tolist()):
            by_loc.setdefault(int(k), []).append(r)
        keep = []
        for o in self.obligations:
            tgt = by_loc.get(o.target, [])
            if not tgt:
                continue
            got = any(delivered[r] for r in tgt)
            placed = all(m not in by_loc or any(at_goal[r] for r in by_loc[m]) for m in o.members)
            if not (got and placed):
                keep.append(o)
        self.obligations = keep

    def ready(self, done: np.ndarray, connected: np.ndarray, goal_keys: np.ndarray) -> np.ndarray:
        """Boolean ``(n,)``: finished at its goal, connected and bound by no obligation."""
        bound_locs: set[int] = set()
        for o in self.obligations:
            bound_locs |= o.members
        bound = np.array([int(k) in bound_locs for k in np.asarray(goal_keys).tolist()], bool)
        return np.asarray(done, bool) & np.asarray(connected, bool) & ~bound
