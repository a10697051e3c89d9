"""Minimum ``0 -> t`` cuts of a fixed directed graph under changing capacities.

The separation of both ILP models (:mod:`.ilp_model`, arc cuts (4); :mod:`.ilp_node`,
node separators) solves one maximum-flow problem per sink with the LP values as
capacities (scaled to integers, so flows are exact). Returned are the two minimum
cuts that do not depend on which maximum flow was found: the sink side of the
source-nearest cut (vertices the source cannot reach in the residual graph) and the
back cut (vertices that reach the sink in it), the nested / back cuts of
Ljubic et al. (Math. Program. 105, 2006) that the paper's [13] uses. Reference:
scipy's ``maximum_flow`` (Dinic); with :func:`tether.jit.enabled` the compiled
Edmonds-Karp of :mod:`.ilp_kernels` (same cuts, tested).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order, maximum_flow

from tether import jit


class FlowGraph:
    """Arcs ``tail[a] -> head[a]`` on ``n`` vertices, laid out once for every max-flow."""

    def __init__(self, tail: np.ndarray, head: np.ndarray, n: int) -> None:
        self.n = n
        self.tail = np.asarray(tail, dtype=np.int64)
        self.head = np.asarray(head, dtype=np.int64)
        # CSR layout (zero capacities stay as explicit entries): only capacities change
        self.csr_order = np.lexsort((self.head, self.tail))
        self.csr_indices = self.head[self.csr_order].astype(np.int32)
        self.out_ptr = np.concatenate([[0], np.cumsum(np.bincount(self.tail, minlength=n))])
        self.out_ptr = self.out_ptr.astype(np.int64)
        self.out_flat = self.csr_order.astype(np.int64)
        self.in_flat = np.argsort(self.head, kind="stable").astype(np.int64)
        self.in_ptr = np.concatenate([[0], np.cumsum(np.bincount(self.head, minlength=n))])
        self.in_ptr = self.in_ptr.astype(np.int64)

    def min_cut(
        self, cap: np.ndarray, t: int, scale: float, enough: float = np.inf
    ) -> tuple[float, np.ndarray, np.ndarray]:
        """Max-flow ``0 -> t`` (divided by ``scale``); sink sides of the two cuts.

        ``cap`` are integer capacities per arc. The compiled kernel may stop once
        the flow reaches ``enough`` (then no cut is wanted and the masks are empty).
        """
        if jit.enabled():
            from tether.recurrent.planning.ilp_kernels import min_cut_kernel

            return min_cut_kernel(
                self.tail, self.head, self.out_ptr, self.out_flat, self.in_ptr, self.in_flat,
                np.asarray(cap, dtype=np.int64), t, enough, float(scale),
            )  # fmt: skip
        g = sp.csr_matrix(
            (cap[self.csr_order].astype(np.int32), self.csr_indices, self.out_ptr.astype(np.int32)),
            shape=(self.n, self.n),
        )
        res = maximum_flow(g, 0, t, method="dinic")
        resid = (g - res.flow).tocsr()
        resid.data = (resid.data > 0).astype(np.int8)
        resid.eliminate_zeros()
        src_side = np.zeros(self.n, dtype=bool)
        src_side[breadth_first_order(resid, 0, directed=True, return_predecessors=False)] = True
        sink_side = np.zeros(self.n, dtype=bool)
        sink_side[
            breadth_first_order(resid.T.tocsr(), t, directed=True, return_predecessors=False)
        ] = True
        return res.flow_value / scale, ~src_side, sink_side
