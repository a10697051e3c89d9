"""The node-separator model of the configuration problem: vertex variables only.

Banfi et al.'s eqs. (2)-(3) with the connectivity constraints (4) written on the
vertices instead of the arcs, as in the node-based model of Fischetti, Leitner,
Ljubic, Luipersbeck, Monaci, Resch, Salvagnin and Sinnl ("Thinning out Steiner trees:
a node-based model for uniform edge costs", Math. Prog. Comp. 9, 2017) and the
rooted connected-subgraph model of Alvarez-Miranda, Ljubic and Mutzel (the paper's
[13]):

    max  sum_f U(f) y_f                                                   (2)
    sum_v y_v <= |R^t|                                                    (3)
    y(N) >= y_k   for every k and every vertex set N separating k from b  (4')

A robot is a vertex, so eq. (3) counts the chosen vertices and no arc variable is
needed: ``n - 1`` binary columns instead of ``A + n - 1`` (on the benchmark graphs
about 120 instead of 1,800). An integral ``y`` satisfies (4') exactly when the chosen
vertices and ``b`` induce a connected subgraph, i.e. when it is a configuration of
the paper (constraint II), so the optimum is the same as that of the arc model of
:mod:`.ilp_model`. Its LP bound after separation was within 0.3 % of the arc model's
on the benchmark instances (equal on three of five).

Separation of (4'): max-flow from ``b`` to ``k`` in the split graph (every vertex
``v`` an arc ``v_in -> v_out`` of capacity ``y_v``, every link ``u_out -> v_in`` of
infinite capacity), whose minimum cuts are vertex separators; nested and back cuts as
in :mod:`.ilp_model`. The initial rows hold (4') for the neighbourhoods
``N = N(k)`` of the vertices not linked to ``b``.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order, connected_components

from tether import jit
from tether.recurrent.planning.ilp_flow import FlowGraph
from tether.recurrent.planning.ilp_model import NESTED, SCALE
from tether.recurrent.planning.problem import Problem

MAX_TARGETS = 200  # sinks tried per separation round, by decreasing y
SKIP_COVERED = True
MINIMAL = True  # no max-flow for a sink behind a cut found in this round

Rows = tuple[list[np.ndarray], list[np.ndarray], list[float], list[float]]


class NodeSeparatorModel:
    """Columns ``y_1..y_{n-1}`` (``n_arcs = 0``); the interface of ``DirectedCutModel``."""

    #: a cut's left-hand side holds ``y`` too: ``y`` may violate (4') both ways (SCIP locks)
    y_both_ways = True

    def __init__(self, problem: Problem, keep: np.ndarray) -> None:
        self.keep = keep
        n = self.n = len(keep)
        self.adj = sp.csr_matrix(problem.adj[keep][:, keep] > 0, dtype=np.int8)
        self.adj.setdiag(0)
        self.adj.eliminate_zeros()
        coo = self.adj.tocoo()
        self.ei, self.ej = coo.row.astype(np.intp), coo.col.astype(np.intp)  # both directions
        self.n_arcs = 0
        self.utility = problem.utility[keep]
        self.budget = problem.budget
        self.n_cols = n - 1
        self.cost = self.utility[1:].astype(float)
        self.conflicts: list[np.ndarray] = []
        self.root_linked = np.zeros(n, dtype=bool)
        self.root_linked[self.adj[0].indices] = True
        # split graph: v_in = v, v_out = n + v; arc v is v_in -> v_out, then the links
        into = self.ej != 0
        tail = np.concatenate([np.arange(n), n + self.ei[into]])
        head = np.concatenate([np.arange(n), self.ej[into]])
        head[:n] += n
        self.flow = FlowGraph(tail, head, 2 * n)
        self.big = (n + 1) * SCALE  # more than any vertex cut

    def ycol(self, v: int) -> int:
        return v - 1

    def base_rows(self) -> Rows:
        """Initial rows ``(cols, coefs, lower, upper)``: the budget (3) and (4') on neighbourhoods.

        (4') with ``N = N(k)`` for every vertex ``k`` not linked to ``b``, and the
        frontier conflict rows of :data:`.ilp_model.CONFLICT_SIZE` (off by default).
        """
        cols = [np.arange(self.n_cols)]
        vals = [np.ones(self.n_cols)]
        lo, hi = [-np.inf], [float(self.budget)]
        for k in range(1, self.n):
            if not self.root_linked[k]:
                sep = self.adj[k].indices
                c, v = self.cut_row(sep - 1, k)
                cols.append(c)
                vals.append(v)
                lo.append(0.0)
                hi.append(np.inf)
        for group in self.conflicts:  # frontier sets no tree within budget can hold (off)
            cols.append(np.asarray(group, dtype=np.intp) - 1)
            vals.append(np.ones(len(group)))
            lo.append(-np.inf)
            hi.append(float(len(group) - 1))
        return cols, vals, lo, hi

    def cut_row(self, cols: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Row ``y(N) - y_k >= 0`` with ``cols`` the columns of the separator ``N``."""
        return np.append(cols, self.ycol(k)), np.append(np.ones(len(cols)), -1.0)

    def solution_vector(self, vertices: set[int], pred: dict[int, int]) -> np.ndarray:
        """Column values of a configuration (``pred`` is not needed)."""
        val = np.zeros(self.n_cols)
        for v in vertices:
            if v != 0:
                val[self.ycol(v)] = 1.0
        return val

    # ------------------------------------------------------------ separation

    def separate_integral(self, x: np.ndarray, y: np.ndarray) -> list[tuple[np.ndarray, int]]:
        """(4') violated by an integral ``y``: ``N = N(C)`` for each component ``C`` cut off."""
        chosen = np.zeros(self.n, dtype=bool)
        chosen[0] = True
        chosen[1:] = y > 0.5
        sub = self.adj[chosen][:, chosen]
        idx = np.flatnonzero(chosen)
        reach = np.zeros(self.n, dtype=bool)
        reach[idx[breadth_first_order(sub, 0, directed=False, return_predecessors=False)]] = True
        lost = np.flatnonzero(chosen & ~reach)
        if len(lost) == 0:
            return []
        ncomp, lab = connected_components(self.adj[lost][:, lost], directed=False)
        cuts = []
        for c in range(ncomp):
            members = lost[lab == c]
            inside = np.zeros(self.n, dtype=bool)
            inside[members] = True
            near = np.asarray(self.adj[members].sum(axis=0)).ravel() > 0
            sep = np.flatnonzero(near & ~inside)  # unchosen: b is not among them
            for k in members[:3]:
                cuts.append((sep - 1, int(k)))
        return cuts

    def separate_fractional(
        self, x: np.ndarray, y: np.ndarray, max_targets: int | None = None
    ) -> list[tuple[np.ndarray, int]]:
        """Max-flow separation of (4') with nested and back cuts."""
        max_targets = MAX_TARGETS if max_targets is None else max_targets
        n = self.n
        yv = np.concatenate([[1.0], np.clip(y, 0.0, 1.0)])
        cap = np.full(len(self.flow.tail), self.big, dtype=np.int64)
        cap[:n] = np.round(yv * SCALE).astype(np.int64)
        cap[0] = self.big
        wide = self.widest_from_root(yv)
        cuts: list[tuple[np.ndarray, int]] = []
        seen: set[bytes] = set()
        done = 0
        covered = np.zeros(n, dtype=bool)
        for t in np.argsort(-yv, kind="stable"):
            if t == 0 or yv[t] < 1e-4 or self.root_linked[t] or covered[t]:
                continue
            if wide[t] >= yv[t]:  # one path carries y_t: no separator is violated
                continue
            if done >= max_targets:
                break
            done += 1
            c = cap.copy()
            for _ in range(NESTED):
                flow, inside, back = self.flow.min_cut(c, int(t), SCALE, yv[t] - 1e-4)
                if flow >= yv[t] - 1e-4:
                    break
                if SKIP_COVERED:  # the round has a cut, so it is not the last one
                    covered |= inside[:n]
                for mask in (inside, back):
                    sep = np.flatnonzero(~mask[:n] & mask[n:])
                    if MINIMAL:
                        sep = self.minimal(sep, int(t))
                    key = sep.tobytes() + int(t).to_bytes(4, "little")
                    if key not in seen:
                        seen.add(key)
                        cuts.append((sep - 1, int(t)))
                c[np.flatnonzero(~inside[:n] & inside[n:])] = self.big  # nested
        return cuts

    def _component(self, start: int, removed: np.ndarray) -> np.ndarray:
        """Mask of the component of ``start`` in the graph without the ``removed`` vertices."""
        keep = ~removed
        idx = np.flatnonzero(keep)
        pos = int(np.searchsorted(idx, start))
        order = breadth_first_order(
            self.adj[idx][:, idx], pos, directed=False, return_predecessors=False
        )
        out = np.zeros(self.n, dtype=bool)
        out[idx[order]] = True
        return out

    def minimal(self, sep: np.ndarray, t: int) -> np.ndarray:
        """A minimal separator inside ``sep``: its vertices next to both sides.

        Vertices of a cut (zero ``y`` ones, typically) with no neighbour in the
        component of ``t`` (then of ``b``) are dropped; the rest still separates, and
        the cut (4') gets fewer terms: stronger, equally violated.
        """
        if jit.enabled():
            from tether.recurrent.planning.ilp_kernels import minimal_separator_kernel

            return minimal_separator_kernel(
                self.adj.indptr, self.adj.indices, sep.astype(np.int64), t
            )
        removed = np.zeros(self.n, dtype=bool)
        removed[sep] = True
        for start in (t, 0):
            comp = self._component(start, removed)
            near = np.zeros(self.n, dtype=bool)
            near[self.ej[comp[self.ei]]] = True
            removed &= near
        return np.flatnonzero(removed)

    def widest_from_root(self, yv: np.ndarray) -> np.ndarray:
        """Largest ``min y`` over the inner vertices of a ``b -> v`` path, for every ``v``.

        A lower bound on the max-flow ``b -> v`` of the split graph, so a sink
        whose widest path carries ``y_v`` needs no max-flow.
        """
        through = yv.copy()
        through[0] = np.inf
        wide = np.zeros(self.n)
        wide[0] = np.inf
        for _ in range(self.n):
            via = np.minimum(wide[self.ei], through[self.ei])
            new = wide.copy()
            np.maximum.at(new, self.ej, via)
            if np.array_equal(new, wide):
                break
            wide = new
        return wide
