"""Optimal deployments: who goes where (Banfi et al., Sec. V).

Given the new configuration ``Q`` for the ready robots, the robots are
assigned to vertices by the Hungarian algorithm minimizing the *total*
travel distance (as in the paper, not the maximum). Two details of Sec. V:

* non-ready robots that can currently exchange data with the base station
  take part in the assignment together with their present goals, so that
  ready and busy robots may swap destinations and avoid crossing paths
  (their goals stay occupied, constraint III; robots that are not connected
  keep their goals, constraint IV);
* if ``Q`` needs fewer robots than are available, the surplus robots are
  assigned, again by the Hungarian algorithm, to "fake frontiers": vertices
  adjacent in ``C^t`` to the configuration ``Q + fixed + {b}``. If there are
  not enough of them, the remaining surplus robots go to the base vertex
  (several robots may wait there), which keeps them connected.
"""

from __future__ import annotations

from collections.abc import Callable, Hashable, Iterable, Mapping
from dataclasses import dataclass

import networkx as nx
import numpy as np
from scipy.optimize import linear_sum_assignment

__all__ = ["Deployment", "optimal_deployment"]

UNREACHABLE_COST = 1e12  # stands in for an infinite travel cost in the assignment


@dataclass(frozen=True)
class Deployment:
    """Result of :func:`optimal_deployment`.

    Attributes
    ----------
    assignment
        ``pi^t``: new goal of every robot that took part (ready robots and
        connected non-ready robots).
    fake_frontiers
        Goals given to surplus robots (not part of ``Q``; the readiness rule
        treats them as frontiers).
    total_cost
        Summed travel cost of the assignment.
    """

    assignment: dict
    fake_frontiers: frozenset
    total_cost: float


def _hungarian(
    robots: list, targets: list, travel_cost: Callable[[Hashable, Hashable], float]
) -> tuple[dict, float]:
    if not robots or not targets:
        return {}, 0.0
    cost = np.array([[float(travel_cost(r, v)) for v in targets] for r in robots])
    cost = np.where(np.isfinite(cost), cost, UNREACHABLE_COST)
    rows, cols = linear_sum_assignment(cost)
    return {robots[i]: targets[j] for i, j in zip(rows, cols, strict=True)}, float(
        cost[rows, cols].sum()
    )


def optimal_deployment(
    graph: nx.Graph,
    base: Hashable,
    configuration: Iterable[Hashable],
    ready: Iterable[Hashable],
    travel_cost: Callable[[Hashable, Hashable], float],
    *,
    connected_busy: Mapping[Hashable, Hashable] | None = None,
    fixed: Iterable[Hashable] = (),
) -> Deployment:
    """Assign robots to the configuration minimizing total travel (Sec. V).

    Parameters
    ----------
    graph
        ``G^t`` (communication edges ``C^t``), for the fake-frontier adjacency.
    base
        Base-station vertex ``b``.
    configuration
        ``Q``: the new vertices (``Configuration.vertices``), ``|Q| <= |R^t|``.
    ready
        Ids of the ready robots ``R^t``.
    travel_cost
        ``travel_cost(robot, vertex)``: travel distance of a robot from where
        it is now to a vertex (the ``d`` of the paper); ``inf`` if unreachable.
    connected_busy
        Non-ready robots currently connected to the BS, with their goals;
        they are re-assigned together with the ready robots.
    fixed
        Goals of all non-ready robots (``Configuration.fixed``); they count
        as part of the configuration for the fake-frontier adjacency.

    Returns
    -------
    Deployment
    """
    q = list(dict.fromkeys(configuration))
    busy = dict(connected_busy or {})
    robots = list(dict.fromkeys([*ready, *busy]))
    targets = list(dict.fromkeys([*q, *busy.values()]))
    if len(targets) > len(robots):
        raise ValueError(f"{len(targets)} goals for {len(robots)} robots")
    assignment, total = _hungarian(robots, targets, travel_cost)
    surplus = [r for r in robots if r not in assignment]
    fakes: set = set()
    if surplus:
        occupied = set(targets) | set(fixed) | {base}
        ring = sorted(
            {u for v in occupied if v in graph for u in graph.neighbors(v)} - occupied,
            key=repr,
        )
        columns = ring + [base] * max(0, len(surplus) - len(ring))
        extra, cost = _hungarian(surplus, columns, travel_cost)
        assignment.update(extra)
        total += cost
        fakes = {v for v in extra.values() if v != base}
    return Deployment(assignment, frozenset(fakes), total)
