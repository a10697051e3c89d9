"""SCIP backend of the directed-cut ILP: a PySCIPOpt constraint handler.

The handler owns the exponential family (4). It separates fractional LP
points by max-flow at every node (``conssepalp``), rejects integral points in
which a chosen vertex is not reachable from the base (``consenfolp``,
``consenfops``, ``conscheck``) and declares variable locks (cuts are
monotone: ``x`` may only help, ``y`` may only hurt).
"""

from __future__ import annotations

import numpy as np
from pyscipopt import SCIP_PARAMSETTING, SCIP_RESULT, Conshdlr, Model, quicksum

from tether.recurrent.planning.ilp_model import DirectedCutModel
from tether.recurrent.planning.ilp_node import NodeSeparatorModel

SCIP_PARAMS: dict = {
    # strong branching is most of the time of the instances that branch; capping the
    # simplex iterations per candidate when initialising pseudocosts cut the CPU time
    # of 10 exploration instances (seeds 0, 4, 6-13) from 31 s to 23 s, hardest 12.5 -> 6.3 s
    "branching/relpscost/inititer": 10,
    # node model: the aggregation (c-MIR) separator ran in every root round and found
    # nearly nothing (seed 1: 0.31 s, 3 cuts); off: seeds 0-4 median 0.35 -> 0.29 s CPU
    "separating/aggregation/freq": -1,
}
SCIP_QUIET = True
HEURISTICS_OFF = True  # the APX incumbent is near-optimal (measured)
SEPARATING: str | None = None  # a SCIP_PARAMSETTING name for SCIP's own separators


class _DirectedCuts(Conshdlr):
    def __init__(self, dm: DirectedCutModel | NodeSeparatorModel, variables: list) -> None:
        self.dm = dm
        self.vars = variables
        self.n_cuts = 0
        self.n_sepa_calls = 0

    def _values(self, sol) -> np.ndarray:
        get = self.model.getSolVal
        return np.fromiter((get(sol, v) for v in self.vars), dtype=float, count=len(self.vars))

    def _split(self, vals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        return vals[: self.dm.n_arcs], vals[self.dm.n_arcs :]

    def _add(self, cuts: list) -> None:
        m = self.model
        for arcs, k in cuts:
            row = m.createEmptyRowUnspec(
                name=f"cut{self.n_cuts}", lhs=0.0, rhs=None, local=False, removable=True
            )
            m.cacheRowExtensions(row)
            for a in arcs:
                m.addVarToRow(row, self.vars[int(a)], 1.0)
            m.addVarToRow(row, self.vars[self.dm.ycol(k)], -1.0)
            m.flushRowExtensions(row)
            m.addCut(row, forcecut=False)
            m.addPoolCut(row)
            self.n_cuts += 1

    def conscheck(
        self, constraints, solution, checkintegrality, checklprows, printreason, completely
    ):
        x, y = self._split(self._values(solution))
        ok = not self.dm.separate_integral(x, y)
        return {"result": SCIP_RESULT.FEASIBLE if ok else SCIP_RESULT.INFEASIBLE}

    def consenfolp(self, constraints, nusefulconss, solinfeasible):
        x, y = self._split(self._values(None))
        cuts = self.dm.separate_integral(x, y)
        if not cuts:
            return {"result": SCIP_RESULT.FEASIBLE}
        self._add(cuts)
        return {"result": SCIP_RESULT.SEPARATED}

    def consenfops(self, constraints, nusefulconss, solinfeasible, objinfeasible):
        x, y = self._split(self._values(None))
        ok = not self.dm.separate_integral(x, y)
        return {"result": SCIP_RESULT.FEASIBLE if ok else SCIP_RESULT.SOLVELP}

    def conssepalp(self, constraints, nusefulconss):
        self.n_sepa_calls += 1
        x, y = self._split(self._values(None))
        cuts = self.dm.separate_fractional(x, y)
        if not cuts:
            return {"result": SCIP_RESULT.DIDNOTFIND}
        self._add(cuts)
        return {"result": SCIP_RESULT.SEPARATED}

    def conslock(self, constraint, locktype, nlockspos, nlocksneg):
        m = self.model
        for a in range(self.dm.n_arcs):  # lowering x may violate (4)
            m.addVarLocksType(self.vars[a], locktype, nlockspos, nlocksneg)
        both = nlockspos + nlocksneg
        for v in range(1, self.dm.n):  # raising y may violate (4); in a separator, lowering too
            if self.dm.y_both_ways:
                m.addVarLocksType(self.vars[self.dm.ycol(v)], locktype, both, both)
            else:
                m.addVarLocksType(self.vars[self.dm.ycol(v)], locktype, nlocksneg, nlockspos)


def solve_scip(
    dm: DirectedCutModel | NodeSeparatorModel, hint, time_limit_s: float | None
) -> tuple[np.ndarray, bool, float, dict]:
    m = Model("configuration")
    m.hideOutput(SCIP_QUIET)
    if HEURISTICS_OFF:
        m.setHeuristics(SCIP_PARAMSETTING.OFF)
    if SEPARATING is not None:
        m.setSeparating(getattr(SCIP_PARAMSETTING, SEPARATING))
    for key, val in SCIP_PARAMS.items():
        m.setParam(key, val)
    m.setParam("parallel/maxnthreads", 1)
    if time_limit_s is not None:
        m.setParam("limits/time", float(time_limit_s))
    variables = [m.addVar(f"x{a}", vtype="B", obj=0.0) for a in range(dm.n_arcs)]
    variables += [m.addVar(f"y{v}", vtype="B", obj=float(dm.utility[v])) for v in range(1, dm.n)]
    m.setMaximize()
    cols, vals, lo, hi = dm.base_rows()
    for c, w, lo_, hi_ in zip(cols, vals, lo, hi, strict=True):
        expr = quicksum(float(wi) * variables[int(ci)] for ci, wi in zip(c, w, strict=True))
        if lo_ == hi_:
            m.addCons(expr == hi_)
        elif np.isfinite(lo_):
            m.addCons(expr >= lo_)
        else:
            m.addCons(expr <= hi_)
    hdlr = _DirectedCuts(dm, variables)
    m.includeConshdlr(
        hdlr,
        "directedcuts",
        "cut constraints (4) separated by max-flow",
        sepapriority=1_000_000,
        enfopriority=-10,
        chckpriority=-10,
        sepafreq=1,
        needscons=True,
    )
    cons = m.createCons(
        hdlr, "dcut", initial=True, separate=True, enforce=True, check=True, propagate=False
    )
    m.addPyCons(cons)
    if hint is not None:
        verts, parent = hint
        start = dm.solution_vector(verts, parent)
        sol = m.createSol()
        for var, val in zip(variables, start, strict=True):
            m.setSolVal(sol, var, float(val))
        m.addSol(sol)
    m.optimize()
    status = m.getStatus()
    best = m.getBestSol()
    values = (
        np.array([m.getSolVal(best, v) for v in variables])
        if m.getNSols()
        else np.zeros(len(variables))
    )
    stats = {
        "status": status,
        "nodes": int(m.getNNodes()),
        "cuts": hdlr.n_cuts,
        "sepa_calls": hdlr.n_sepa_calls,
    }
    return values, status == "optimal", float(m.getDualbound()), stats
