"""HiGHS backend of the directed-cut ILP: a solve-separate-resolve loop.

1. LP phase: solve the LP relaxation, separate cuts (4) by max-flow, add
   them, resolve, until no cut is violated (or ``LP_ROUNDS`` rounds).
2. MIP phase: solve the MIP with the cuts found so far and the APX
   incumbent; if a chosen vertex of the integer solution is not reachable
   from the base, add the violated cuts and resolve. The first connected
   MIP optimum is optimal for the full model, since the model solved is a
   relaxation of it.
"""

from __future__ import annotations

import time

import highspy
import numpy as np
import scipy.sparse as sp

from tether.recurrent.planning.ilp_model import DirectedCutModel
from tether.recurrent.planning.ilp_node import NodeSeparatorModel

LP_ROUNDS = 200
HIGHS_OPTIONS: dict = {
    # node model, seed 0: RINS / RENS sub-MIPs were 3.9 of 6.5 s after the root had the
    # optimum (feasibility jump found it at once); off: 8.5 -> 5.3 s CPU, seeds 1-4 alike
    "mip_heuristic_run_rins": False,
    "mip_heuristic_run_rens": False,
}


def _rows_csr(cols: list, vals: list, n_cols: int) -> sp.csr_matrix:
    indptr = np.concatenate([[0], np.cumsum([len(c) for c in cols])])
    return sp.csr_matrix(
        (np.concatenate(vals), np.concatenate(cols).astype(np.int32), indptr),
        shape=(len(cols), n_cols),
    )


def _add_cuts(h: highspy.Highs, dm: DirectedCutModel | NodeSeparatorModel, cuts: list) -> None:
    rows = [dm.cut_row(arcs, k) for arcs, k in cuts]
    mat = _rows_csr([r[0] for r in rows], [r[1] for r in rows], dm.n_cols)
    h.addRows(
        len(rows),
        np.zeros(len(rows)),
        np.full(len(rows), highspy.kHighsInf),
        mat.nnz,
        mat.indptr[:-1].astype(np.int32),
        mat.indices.astype(np.int32),
        mat.data.astype(float),
    )


def solve_highs(
    dm: DirectedCutModel | NodeSeparatorModel, hint, time_limit_s: float | None
) -> tuple[np.ndarray, bool, float, dict]:
    t0 = time.perf_counter()
    deadline = None if time_limit_s is None else t0 + float(time_limit_s)
    h = highspy.Highs()
    h.silent()
    h.setOptionValue("threads", 1)
    h.setOptionValue("mip_rel_gap", 0.0)
    h.setOptionValue("mip_abs_gap", 1e-9)
    for key, val in HIGHS_OPTIONS.items():
        h.setOptionValue(key, val)
    cols, vals, lo, hi = dm.base_rows()
    mat = _rows_csr(cols, vals, dm.n_cols)
    lp = highspy.HighsLp()
    lp.num_col_ = dm.n_cols
    lp.num_row_ = len(cols)
    lp.col_cost_ = dm.cost
    lp.col_lower_ = np.zeros(dm.n_cols)
    lp.col_upper_ = np.ones(dm.n_cols)
    inf = highspy.kHighsInf
    lp.row_lower_ = np.where(np.isfinite(lo), lo, -inf)
    lp.row_upper_ = np.where(np.isfinite(hi), hi, inf)
    lp.sense_ = highspy.ObjSense.kMaximize
    lp.a_matrix_.format_ = highspy.MatrixFormat.kRowwise
    lp.a_matrix_.start_ = mat.indptr.astype(np.int32)
    lp.a_matrix_.index_ = mat.indices.astype(np.int32)
    lp.a_matrix_.value_ = mat.data.astype(float)
    lp.a_matrix_.num_col_ = dm.n_cols
    lp.a_matrix_.num_row_ = len(cols)
    h.passModel(lp)
    n_cuts, lp_rounds, mip_rounds = 0, 0, 0

    def remaining() -> float | None:
        return None if deadline is None else max(deadline - time.perf_counter(), 0.0)

    for _ in range(LP_ROUNDS):  # LP phase
        if deadline is not None:
            if remaining() <= 0:
                break
            h.setOptionValue("time_limit", remaining())
        h.run()
        lp_rounds += 1
        x = np.asarray(h.getSolution().col_value)
        cuts = dm.separate_fractional(x[: dm.n_arcs], x[dm.n_arcs :])
        if not cuts:
            break
        _add_cuts(h, dm, cuts)
        n_cuts += len(cuts)
    h.changeColsIntegrality(
        dm.n_cols, np.arange(dm.n_cols, dtype=np.int32), np.full(dm.n_cols, 1, dtype=np.uint8)
    )
    values = np.zeros(dm.n_cols)
    proven, bound = False, float("inf")
    if hint is not None:
        values = dm.solution_vector(*hint)
    while True:  # MIP phase
        rem = remaining()
        if rem is not None:
            if rem <= 0:
                break
            h.setOptionValue("time_limit", rem)
        if hint is not None:
            start = dm.solution_vector(*hint)
            h.setSolution(dm.n_cols, np.arange(dm.n_cols, dtype=np.int32), start)
        h.run()
        mip_rounds += 1
        info = h.getInfo()
        status = h.getModelStatus()
        x = np.asarray(h.getSolution().col_value)
        if len(x) != dm.n_cols or info.primal_solution_status == 0:
            break
        cuts = dm.separate_integral(x[: dm.n_arcs], x[dm.n_arcs :])
        if not cuts:
            values = x
            proven = status == highspy.HighsModelStatus.kOptimal
            bound = float(info.mip_dual_bound)
            break
        _add_cuts(h, dm, cuts)
        n_cuts += len(cuts)
    stats = {"cuts": n_cuts, "lp_rounds": lp_rounds, "mip_rounds": mip_rounds}
    return values, proven, bound, stats
