"""Exact optimal configurations: the ILP of Banfi et al., eqs. (2)-(4).

Two models with the same optimum, chosen by :data:`FORMULATION`: the
node-separator model of :mod:`.ilp_node` (the default: vertex variables only,
(4) on vertex separators; about 10 times faster on the benchmark, see
``docs/explanation/recurrent_planning.md``) and the paper's directed-cut model below
(:mod:`.ilp_model`). Both share the reductions, the APX incumbent and the
backends.

Directed-cut model on the transformed graph of Sec. IV-A (root ``b`` = index 0, arcs in
both directions except into ``b``), solved by branch-and-cut:

    max  sum_f U(f) y_f                                        (2)
    sum_v y_v <= |R^t|                                         (3)
    x(delta^-(S)) >= y_k   for all S not containing b, k in S  (4)

with binary arc variables ``x`` and vertex variables ``y``. The paper's (4) is
stated for frontiers; as in the B-RMWCS formulation it is taken from
(Alvarez-Miranda, Ljubic, Mutzel 2013, the paper's [13]), we keep a ``y`` for
every vertex and add valid equalities and inequalities that make the LP
relaxation strong without changing the optimum:

* in-degree: ``x(delta^-(v)) = y_v`` (the solution is an arborescence, so its
  arc count equals its vertex count and (3) counts robots);
* 2-cycles: ``x_ij + x_ji <= y_i`` for ``i, j != b``;
* no useless leaves: ``y_v <= x(delta^+(v))`` for non-frontiers ``v`` (a
  non-frontier leaf can be dropped without loss).

Cuts (4) are separated by max-flow (``scipy.sparse.csgraph.maximum_flow``)
from ``b`` to every vertex with positive ``y``, with nested cuts (saturate
the cut found, search again) and back cuts (the minimum cut closest to the
sink), as the paper does with Gurobi following [13].

Before the solve, two more exact reductions shrink the graph: vertices whose
neighbourhood is contained in the closed neighbourhood of another vertex are
removed if they are not frontiers (any tree through them can use the
dominating vertex instead, at the same or lower robot count), and the hop
reductions of :mod:`.problem` are re-applied. The APX solution (Algorithm 1,
``delta = 4``) is passed to the solver as the starting incumbent.
"""

from __future__ import annotations

import time

import numpy as np
from scipy.sparse.csgraph import breadth_first_order, shortest_path

from tether.recurrent.planning.apx import solve_apx
from tether.recurrent.planning.ilp_model import (
    CONFLICT_SIZE,
    DirectedCutModel,
    IlpResult,
    frontier_conflicts,
    reduce_dominated,
)
from tether.recurrent.planning.ilp_node import NodeSeparatorModel
from tether.recurrent.planning.problem import UNREACHABLE, Problem

#: ``"node"``: vertex variables and node-separator cuts (:mod:`.ilp_node`);
#: ``"arc"``: the directed-cut model of the paper's (4) (:mod:`.ilp_model`)
FORMULATION = "node"


def _incumbent(problem: Problem, keep: np.ndarray) -> tuple[set[int], dict[int, int]] | None:
    """APX (delta = 4) on the reduced graph, as a tree with parent pointers."""
    adj = problem.adj[keep][:, keep]
    dist_f, pred = shortest_path(adj, unweighted=True, directed=False, return_predecessors=True)
    dist = np.where(np.isfinite(dist_f), dist_f, UNREACHABLE).astype(np.int32)
    sub = Problem(
        [problem.labels[i] for i in keep],
        adj,
        dist,
        pred,
        problem.utility[keep],
        problem.budget,
        problem.fixed,
    )
    verts = solve_apx(sub, 4).vertices
    if len(verts) <= 1:
        return None
    idx = np.fromiter(sorted(verts), dtype=np.intp)
    order, preds = breadth_first_order(adj[idx][:, idx], 0, directed=False)
    if len(order) != len(idx):
        return None
    parent = {int(idx[v]): int(idx[p]) for v, p in enumerate(preds) if p >= 0}
    return verts, parent


def _decode(model: DirectedCutModel | NodeSeparatorModel, values: np.ndarray) -> set[int]:
    y = values[model.n_arcs :]
    return {0} | {int(v) for v in np.flatnonzero(y > 0.5) + 1}


def solve_ilp(
    problem: Problem, backend: str = "scip", time_limit_s: float | None = None
) -> IlpResult:
    """Solve eqs. (2)-(4) to proven optimality (see the module docstring).

    ``time_limit_s`` bounds the whole call (reductions, incumbent and solver):
    when it runs out, the best solution found is returned with
    ``proven_optimal=False`` (at worst the APX incumbent). The phases before the
    solver are not interrupted; the budget is checked between them, and a call
    out of time before the solver returns no solution (``{0}``, the caller's
    APX fallback takes over).
    """
    t0 = time.perf_counter()
    if problem.budget == 0 or not np.any(problem.utility > 0):
        return IlpResult({0}, 0.0, True, 0.0, {})
    if time_limit_s is not None and time_limit_s <= 0:
        return IlpResult({0}, 0.0, False, float("inf"), {"solver_skipped": True})

    def out_of_time() -> bool:
        return time_limit_s is not None and time.perf_counter() - t0 >= time_limit_s

    skipped = IlpResult({0}, 0.0, False, float("inf"), {"solver_skipped": True})
    keep = reduce_dominated(problem)
    if out_of_time():  # the phases before the solver are not interrupted, but checked
        return skipped
    model = (NodeSeparatorModel if FORMULATION == "node" else DirectedCutModel)(problem, keep)
    if out_of_time():
        return skipped
    if CONFLICT_SIZE >= 2:
        model.conflicts = frontier_conflicts(problem, keep, CONFLICT_SIZE)
    hint = _incumbent(problem, keep)
    stats = {
        "n_reduced": int(model.n),
        "arcs": int(model.n_arcs),
        "reduce_s": time.perf_counter() - t0,
    }
    if backend == "scip":
        # the solver libraries load only when asked for (0.2-0.3 s of import each)
        from tether.recurrent.planning.ilp_scip import solve_scip as run
    elif backend == "highs":
        from tether.recurrent.planning.ilp_highs import solve_highs as run
    else:
        raise ValueError(f"unknown ILP backend {backend!r}; expected 'scip' or 'highs'")
    # the time limit is the budget of the whole call: what the reductions and the
    # incumbent took is no longer available to the solver
    left = None if time_limit_s is None else time_limit_s - (time.perf_counter() - t0)
    if left is not None and left <= 0:  # out of time already: the incumbent
        values = np.zeros(model.n_cols) if hint is None else model.solution_vector(*hint)
        proven, bound, more = False, float("inf"), {"solver_skipped": True}
    else:
        values, proven, bound, more = run(model, hint, left)
    stats.update(more)
    stats["incumbent_utility"] = (  # the hint is indexed on the reduced graph
        0.0 if hint is None else float(problem.utility[keep[sorted(hint[0])]].sum())
    )
    local = _decode(model, values)
    verts = {int(keep[v]) for v in local}
    utility = float(problem.utility[list(verts)].sum())
    return IlpResult(verts, utility, proven, max(bound, utility), stats)
