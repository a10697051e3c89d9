"""The optimal configuration problem of recurrent-connectivity exploration.

Banfi, Quattrini Li, Basilico, Rekleitis, Amigoni, "Asynchronous multirobot
exploration under recurrent connectivity constraints" (ICRA 2016), Sec. III-IV.

Model (exactly the paper's)
---------------------------
* ``graph`` is ``G^t = (V^t, C^t)``: vertices are known locations, edges are
  the communication links ``C^t`` (not travel edges). It is undirected and
  unweighted: every vertex of a configuration costs one robot.
* ``base`` is the base-station vertex ``b``. It is always "occupied" (by the
  BS) and never consumes budget; a utility given for it is ignored.
* ``utilities`` maps each frontier ``f in F^t`` to ``U(f) >= 0`` (eq. 1,
  ``g(f) / min_j d(p_j, f)^2``, computed by the caller). Other vertices have
  utility 0; frontiers with ``U(f) = 0`` add nothing.
* ``budget`` is ``|R^t|``, the number of ready robots.
* ``fixed`` (keyword, default empty) are the goal vertices of the robots that
  are *not* ready. They stay in the configuration (constraint III) and act as
  relays: Sec. IV-A replaces them by fictitious edges from their neighbours
  to ``b`` (see :func:`tether.recurrent.planning.problem.build`).

A configuration is a set ``Q`` of vertices for the ready robots with
``|Q| <= budget``, ``b`` and ``fixed`` excluded, such that ``Q + fixed + {b}``
is connected in ``G^t`` (constraint II) and, whenever possible, ``Q`` holds a
frontier (constraint I). Its utility is ``U(Q) = sum_{f in Q} U(f)``; the
optimal configuration maximizes it (eq. 2). ``Q`` is the vertex set of a tree
hanging from ``b``, with ``|Q|`` = its number of edges (eq. 3).

Methods
-------
``"ilp"``
    Eqs. (2)-(4) solved to proven optimality by branch-and-cut, the cut
    constraints (4) separated by max-flow (``backend="scip"``: a PySCIPOpt
    constraint handler; ``backend="highs"``: a HiGHS solve-separate-resolve
    loop). See :mod:`tether.recurrent.planning.ilp`.
``"apx"``
    Algorithm 1 with ``delta``: a ``k/delta`` approximation,
    ``k = min(|R^t|, |F^t|)``, exact when the optimum uses at most ``delta``
    frontiers (Theorem 4.1). See :mod:`tether.recurrent.planning.apx`.
"""

from __future__ import annotations

import time
from collections.abc import Hashable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Literal

import networkx as nx

from tether.recurrent.planning import problem as _problem
from tether.recurrent.planning.apx import solve_apx
from tether.recurrent.planning.ilp import solve_ilp

__all__ = ["Configuration", "check_configuration", "optimal_configuration"]


@dataclass(frozen=True)
class Configuration:
    """A planned configuration for the ready robots.

    Attributes
    ----------
    vertices
        ``Q``: the vertices the ready robots must occupy (``b`` and the
        non-ready goals excluded). Empty if no frontier is reachable.
    utility
        ``U(Q)``, the summed utility of the frontiers in ``Q``.
    robots_used
        ``|Q|`` (at most the budget); the other ready robots are surplus
        (see :mod:`tether.recurrent.deployment`, "fake frontiers").
    method
        ``"apx"``, ``"ilp-scip"`` or ``"ilp-highs"``.
    solve_time_s
        Wall-clock planning time including the graph transformation.
    proven_optimal
        True if ``utility`` is proven to be the optimum of eq. (2).
    upper_bound
        A proven upper bound on the optimum (ILP dual bound; for APX the
        Theorem 4.1 bound ``(k/delta) U(F^delta-BEST)``).
    fixed
        The non-ready goals that were treated as relays.
    timed_out
        The ILP's time budget ran out before optimality was proven: the
        configuration is the best one found (``proven_optimal`` is false).
    fallback
        True when that best configuration is the APX one (Algorithm 1, the
        solver found nothing better within the budget).
    apx_delta
        The ``delta`` APX ran with (:func:`~tether.recurrent.planning.apx.apx_delta`),
        None if it did not run.
    apx_delta_capped
        True if :data:`~tether.recurrent.planning.apx.MAX_TABLE_SUBSETS` lowered it.
    """

    vertices: frozenset
    utility: float
    robots_used: int
    method: str
    solve_time_s: float
    proven_optimal: bool
    upper_bound: float = float("inf")
    fixed: frozenset = field(default_factory=frozenset)
    timed_out: bool = False
    fallback: bool = False
    apx_delta: int | None = None
    apx_delta_capped: bool = False

    @property
    def occupied(self) -> frozenset:
        """The full paper configuration ``Q^t``: new vertices plus non-ready goals."""
        return self.vertices | self.fixed


def optimal_configuration(
    graph: nx.Graph,
    base: Hashable,
    utilities: Mapping[Hashable, float],
    budget: int,
    method: Literal["apx", "ilp"] = "apx",
    delta: int = 4,
    *,
    fixed: Iterable[Hashable] = (),
    backend: Literal["scip", "highs"] = "scip",
    time_limit_s: float | None = None,
) -> Configuration:
    """Best connected configuration of at most ``budget`` robots (Sec. IV).

    Parameters
    ----------
    graph
        ``G^t``: communication graph on the known vertices (see module docstring).
    base
        The base-station vertex ``b``.
    utilities
        ``U(f)`` of each frontier (eq. 1), finite and ``>= 0``.
    budget
        ``|R^t|``, number of ready robots.
    method
        ``"apx"`` (Algorithm 1) or ``"ilp"`` (exact branch-and-cut).
    delta
        Maximum number of frontiers in the subsets enumerated by ``"apx"``.
    fixed
        Goal vertices of the non-ready robots (relays, kept in ``Q^t``).
    backend
        ILP solver: ``"scip"`` (constraint handler) or ``"highs"`` (cut loop).
    time_limit_s
        Optional time budget of an ``"ilp"`` plan, counted from the call (graph
        transformation, reductions and the solver). When it runs out the best
        configuration found is returned with ``proven_optimal=False`` and
        ``timed_out=True``; that is never worse than APX (``delta``), which is
        computed first and returned (``fallback=True``) if the solver found
        nothing better.

    Returns
    -------
    Configuration
    """
    t0 = time.perf_counter()
    problem = _problem.build(graph, base, utilities, budget, fixed)
    timed_out = fallback = False
    apx_run = None
    if method == "apx":
        if int(delta) != delta or delta < 1:
            raise ValueError(f"delta must be a positive integer (got {delta!r})")
        res = apx_run = solve_apx(problem, int(delta))
        verts, util, proven, upper, name = (
            res.vertices,
            res.utility,
            res.proven_optimal,
            res.upper_bound,
            "apx",
        )
    elif method == "ilp":
        apx = None
        if time_limit_s is not None:  # the fallback, computed first
            apx = apx_run = solve_apx(problem, int(delta))
        left = None if time_limit_s is None else time_limit_s - (time.perf_counter() - t0)
        res = solve_ilp(problem, backend=backend, time_limit_s=left)
        verts, util, proven, upper, name = (
            res.vertices,
            res.utility,
            res.proven_optimal,
            res.upper_bound,
            f"ilp-{backend}",
        )
        timed_out = not proven and time_limit_s is not None
        if apx is not None and timed_out:
            if apx.utility > util + 1e-12:
                verts, util = apx.vertices, apx.utility
            # nothing better than APX (or than the solver's APX incumbent) was found
            fallback = util <= max(apx.utility, res.stats.get("incumbent_utility", 0.0)) + 1e-12
    else:
        raise ValueError(f"unknown method {method!r}; expected 'apx' or 'ilp'")
    chosen = problem.to_labels(verts)
    return Configuration(
        vertices=chosen,
        utility=float(sum(problem.utility[i] for i in verts)),
        robots_used=len(chosen),
        method=name,
        solve_time_s=time.perf_counter() - t0,
        proven_optimal=proven,
        upper_bound=max(upper, util),
        fixed=problem.fixed,
        timed_out=timed_out,
        fallback=fallback,
        apx_delta=None if apx_run is None else apx_run.delta_used,
        apx_delta_capped=apx_run is not None and apx_run.delta_capped,
    )


def check_configuration(
    graph: nx.Graph,
    base: Hashable,
    vertices: Iterable[Hashable],
    frontiers: Iterable[Hashable],
    budget: int,
    *,
    fixed: Iterable[Hashable] = (),
    assignment: Mapping[Hashable, Hashable] | None = None,
    previous_goals: Mapping[Hashable, Hashable] | None = None,
    ready: Iterable[Hashable] | None = None,
    connected: Iterable[Hashable] = (),
) -> list[str]:
    """Violations of constraints (I)-(IV) of Sec. III by a plan; ``[]`` if valid.

    Parameters
    ----------
    graph, base, budget
        ``G^t``, ``b``, ``|R^t|`` as for :func:`optimal_configuration`.
    vertices
        The new vertices ``Q`` for the ready robots (``Configuration.vertices``).
    frontiers
        ``F^t`` (e.g. the keys of the utilities).
    fixed
        Goals of the non-ready robots; ``Q^t = vertices + fixed``.
    assignment
        Optional deployment ``pi^t``: robot -> new goal (all robots that got a
        goal, including re-assigned non-ready ones and surplus robots sent to
        fake frontiers).
    previous_goals
        Goals before this plan, needed for (III) and (IV) (robot -> vertex).
    ready
        ``R^t``; robots of ``previous_goals`` not in it are non-ready.
    connected
        Non-ready robots currently able to exchange data with the BS (they may
        be re-assigned, constraint IV).

    Checks
    ------
    budget: ``|Q| <= budget``, ``Q`` disjoint from ``fixed + {b}``;
    (I) ``Q^t`` holds a frontier; (II) ``Q^t + {b}`` connected in ``G^t``;
    (III) every non-ready robot's previous goal is in ``Q^t``;
    (IV) non-ready robots not in ``connected`` keep their goal. With an
    assignment also: every vertex of ``Q`` gets a robot, no two robots share
    a vertex other than ``b``, and all assigned goals plus ``b`` and ``fixed`` are connected.
    """
    q = set(vertices)
    fixed_set = set(fixed)
    out: list[str] = []
    unknown = [v for v in q | fixed_set | {base} if v not in graph]
    if unknown:
        return [f"vertices not in the graph: {sorted(map(repr, unknown))}"]
    if len(q) > budget:
        out.append(f"budget: {len(q)} vertices for {budget} ready robots")
    if base in q:
        out.append("budget: the base station vertex is not a robot goal")
    if q & fixed_set:
        out.append(f"budget: vertices already assigned to non-ready robots: {q & fixed_set}")
    full = q | fixed_set
    if not full & set(frontiers):
        out.append("(I): the configuration holds no frontier")
    if not nx.is_connected(graph.subgraph(full | {base})):
        out.append("(II): Q^t + {b} is not connected in G^t")
    if previous_goals is not None and ready is not None:
        ready_set = set(ready)
        conn = set(connected)
        for r, goal in previous_goals.items():
            if r in ready_set:
                continue
            if goal not in full:
                out.append(f"(III): goal {goal!r} of non-ready robot {r!r} dropped")
            if assignment is not None and r not in conn and assignment.get(r, goal) != goal:
                out.append(f"(IV): non-connected robot {r!r} was re-assigned")
    if assignment is not None:
        goals = [g for g in assignment.values() if g != base]  # robots may wait at b
        if len(set(goals)) != len(goals):
            out.append("deployment: two robots share a goal")
        missing = q - set(goals)
        if missing:
            out.append(f"deployment: vertices with no robot: {missing}")
        if not nx.is_connected(graph.subgraph(set(goals) | fixed_set | {base})):
            out.append("(II): the deployed goals + {b} are not connected in G^t")
    return out
