"""The directed-cut model of eqs. (2)-(4): variables, rows, cut separation.

Banfi et al., Sec. IV-A; shared by the SCIP and HiGHS drivers
(:mod:`.ilp_scip`, :mod:`.ilp_highs`) and built by :func:`.ilp.solve_ilp`,
whose module docstring describes the formulation and the reductions.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp
from scipy.sparse.csgraph import breadth_first_order, shortest_path

from tether.recurrent.planning.apx import SharedSteiner
from tether.recurrent.planning.ilp_flow import FlowGraph
from tether.recurrent.planning.problem import Problem

EPS = 1e-6
SCALE = 1_000_000  # max-flow capacities are x* scaled to integers
NESTED = 3
CONFLICT_SIZE = 0  # frontier conflict rows up to this size; 0 = off (measured: no gain)
CREEP = 0  # added to every positive capacity (0 disables)


@dataclass
class IlpResult:
    vertices: set[int]
    utility: float
    proven_optimal: bool
    upper_bound: float
    stats: dict = field(default_factory=dict)


# ---------------------------------------------------------------- reductions


def reduce_dominated(problem: Problem) -> np.ndarray:
    """Indices kept after removing dominated non-frontier vertices (root kept)."""
    n = problem.n
    a = problem.adj.toarray() > 0
    alive = np.ones(n, dtype=bool)
    frontier = problem.utility > 0
    for _ in range(3):
        changed = False
        aa = a & alive[None, :] & alive[:, None]
        closed = aa | np.eye(n, dtype=bool)
        inter = aa.astype(np.int32) @ closed.T.astype(np.int32)  # |N(v) & N[u]|
        for v in range(1, n):
            if not alive[v] or frontier[v]:
                continue
            nv = aa[v] & alive
            cand = np.flatnonzero(alive & (inter[v] >= nv.sum()))
            cand = cand[cand != v]
            for u in cand:  # recheck against the current (already reduced) graph
                nu = closed[u] & alive
                if not np.any(nv & ~nu & (np.arange(n) != u)):
                    alive[v] = False
                    changed = True
                    break
        if not changed:
            break
    # hop reductions again on the smaller graph
    keep = np.flatnonzero(alive)
    sub = problem.adj[keep][:, keep]
    dist = shortest_path(sub, unweighted=True, directed=False)
    fr = np.flatnonzero(problem.utility[keep] > 0)
    if len(fr) == 0:
        return keep[:1]
    ok = dist[0] + dist[fr].min(axis=0) <= problem.budget
    ok[0] = True
    return keep[ok]


# ---------------------------------------------------------------- the model


class DirectedCutModel:
    """Arrays describing the ILP; columns are ``x_0..x_{A-1}`` then ``y_1..y_{n-1}``."""

    #: ``y`` appears in cuts (4) only with a negative sign (SCIP's variable locks)
    y_both_ways = False

    def __init__(self, problem: Problem, keep: np.ndarray) -> None:
        self.keep = keep
        n = self.n = len(keep)
        adj = sp.triu(problem.adj[keep][:, keep], k=1).tocoo()
        i, j = adj.row.astype(np.intp), adj.col.astype(np.intp)
        # root arcs only leave the root
        root_edge = i == 0
        tail = np.concatenate([i, j[~root_edge]])
        head = np.concatenate([j, i[~root_edge]])
        self.tail, self.head = tail, head
        self.n_arcs = len(tail)
        self.utility = problem.utility[keep]
        self.budget = problem.budget
        self.n_cols = self.n_arcs + n - 1
        self.cost = np.zeros(self.n_cols)
        self.cost[self.n_arcs :] = self.utility[1:]
        self.in_arcs = [np.flatnonzero(head == v) for v in range(n)]
        self.out_arcs = [np.flatnonzero(tail == v) for v in range(n)]
        # reverse arc of each arc (or -1 for root arcs)
        pair = {(int(t), int(h)): a for a, (t, h) in enumerate(zip(tail, head, strict=True))}
        self.conflicts: list[np.ndarray] = []
        self.rev = np.array(
            [pair.get((int(h), int(t)), -1) for t, h in zip(tail, head, strict=True)]
        )
        self.flow = FlowGraph(tail, head, n)  # max-flow layout, built once

    def ycol(self, v: int) -> int:
        return self.n_arcs + v - 1

    def base_rows(self) -> tuple[list[np.ndarray], list[np.ndarray], list[float], list[float]]:
        """Rows ``(cols, coefs, lower, upper)`` of the initial formulation."""
        cols, vals, lo, hi = [], [], [], []
        inf = np.inf
        for v in range(1, self.n):  # in-degree
            cols.append(np.append(self.in_arcs[v], self.ycol(v)))
            vals.append(np.append(np.ones(len(self.in_arcs[v])), -1.0))
            lo.append(0.0)
            hi.append(0.0)
        cols.append(np.arange(self.n_arcs, self.n_cols))  # budget, eq. (3)
        vals.append(np.ones(self.n - 1))
        lo.append(-inf)
        hi.append(float(self.budget))
        for a in range(self.n_arcs):  # 2-cycles: x_ij + x_ji <= y_i
            r = self.rev[a]
            t = int(self.tail[a])
            if r > a and t != 0:
                for end in (t, int(self.head[a])):
                    cols.append(np.array([a, r, self.ycol(end)]))
                    vals.append(np.array([1.0, 1.0, -1.0]))
                    lo.append(-inf)
                    hi.append(0.0)
        for v in range(1, self.n):  # no useless leaves
            if self.utility[v] <= 0:
                cols.append(np.append(self.out_arcs[v], self.ycol(v)))
                vals.append(np.append(-np.ones(len(self.out_arcs[v])), 1.0))
                lo.append(-inf)
                hi.append(0.0)
        for group in self.conflicts:  # frontier sets no tree within budget can hold
            cols.append(np.array([self.ycol(int(v)) for v in group]))
            vals.append(np.ones(len(group)))
            lo.append(-inf)
            hi.append(float(len(group) - 1))
        return cols, vals, lo, hi

    def cut_row(self, arcs: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Row ``x(arcs) - y_k >= 0`` of a cut (4)."""
        return np.append(arcs, self.ycol(k)), np.append(np.ones(len(arcs)), -1.0)

    def solution_vector(self, vertices: set[int], pred: dict[int, int]) -> np.ndarray:
        """Column values of a tree given by parent pointers (keep-indexed)."""
        val = np.zeros(self.n_cols)
        index = {
            (int(t), int(h)): a for a, (t, h) in enumerate(zip(self.tail, self.head, strict=True))
        }
        for v in vertices:
            if v == 0:
                continue
            val[self.ycol(v)] = 1.0
            val[index[(pred[v], v)]] = 1.0
        return val

    # ------------------------------------------------------------ separation

    def arcs_into(self, inside: np.ndarray) -> np.ndarray:
        """Arcs entering the vertex set marked by the boolean mask ``inside``."""
        return np.flatnonzero(~inside[self.tail] & inside[self.head])

    def separate_integral(self, x: np.ndarray, y: np.ndarray) -> list[tuple[np.ndarray, int]]:
        """Cuts violated by an integral point: chosen vertices unreachable from b."""
        used = x > 0.5
        g = sp.csr_matrix(
            (np.ones(int(used.sum())), (self.tail[used], self.head[used])), shape=(self.n, self.n)
        )
        reach = np.zeros(self.n, dtype=bool)
        reach[breadth_first_order(g, 0, directed=True, return_predecessors=False)] = True
        chosen = np.zeros(self.n, dtype=bool)
        chosen[1:] = y > 0.5
        lost = np.flatnonzero(chosen & ~reach)
        if len(lost) == 0:
            return []
        cuts = [(self.arcs_into(~reach), int(lost[0]))]
        # the components of the unreachable part give smaller, stronger cuts
        sub = g[lost][:, lost]
        from scipy.sparse.csgraph import connected_components

        ncomp, lab = connected_components(sub, directed=True, connection="weak")
        for c in range(ncomp):
            members = lost[lab == c]
            inside = np.zeros(self.n, dtype=bool)
            inside[members] = True
            for k in members[:3]:
                cuts.append((self.arcs_into(inside), int(k)))
        return cuts

    def separate_fractional(
        self, x: np.ndarray, y: np.ndarray, max_targets: int = 200
    ) -> list[tuple[np.ndarray, int]]:
        """Max-flow separation of (4) with nested and back cuts."""
        cap = np.round(np.clip(x, 0, 1) * SCALE).astype(np.int64)
        cap[cap > 0] += CREEP  # creep flow: among minimum cuts prefer few arcs
        yv = np.concatenate([[1.0], y])
        targets = np.argsort(-yv)
        wide = self.widest_from_root(x)
        cuts: list[tuple[np.ndarray, int]] = []
        seen: set[bytes] = set()
        done = 0
        for t in targets:
            if t == 0 or yv[t] < 1e-4:
                continue
            if wide[t] >= yv[t]:  # one path carries y_t: max-flow >= y_t, no cut
                continue
            if done >= max_targets:
                break
            done += 1
            c = cap.copy()
            for _ in range(NESTED):
                flow, inside, back = self._min_cut(c, int(t), yv[t] - 1e-4)
                if flow >= yv[t] - 1e-4:
                    break
                for mask in (inside, back):
                    arcs = self.arcs_into(mask)
                    key = arcs.tobytes() + int(t).to_bytes(4, "little")
                    if key not in seen:
                        seen.add(key)
                        cuts.append((arcs, int(t)))
                c[self.arcs_into(inside)] = SCALE  # nested: saturate and search again
        return cuts

    def widest_from_root(self, x: np.ndarray) -> np.ndarray:
        """Bottleneck capacity of the widest ``b -> v`` path for every ``v``.

        A lower bound on the max-flow value ``b -> v``: sinks whose widest
        path already carries ``y_v`` cannot violate a cut (4) and need no
        max-flow. Bellman-Ford style ``w[v] = max_{(u,v)} min(w[u], x_uv)``.
        """
        wide = np.zeros(self.n)
        wide[0] = np.inf
        for _ in range(self.n):
            via = np.minimum(wide[self.tail], x)
            new = wide.copy()
            np.maximum.at(new, self.head, via)
            if np.array_equal(new, wide):
                break
            wide = new
        return wide

    def _min_cut(
        self, cap: np.ndarray, t: int, enough: float = np.inf
    ) -> tuple[float, np.ndarray, np.ndarray]:
        """Max-flow ``b -> t``; sink sides of the source-nearest and back cuts."""
        return self.flow.min_cut(cap, t, SCALE, enough)


def frontier_conflicts(problem: Problem, keep: np.ndarray, max_size: int) -> list[np.ndarray]:
    """Minimal sets of 2..max_size frontiers whose Steiner tree with b exceeds the budget.

    ``sum_{f in S} y_f <= |S| - 1`` is then valid: such frontiers never share
    a configuration. The Steiner costs come from the shared DP of APX.
    Returned as keep-indexed vertex arrays.
    """
    budget = problem.budget
    fr = problem.frontiers
    fr = fr[problem.dist[0, fr] <= budget]
    if len(fr) < 2:
        return []
    dp = SharedSteiner(problem.dist, fr, budget, max_size)
    dp.top_costs(np.flatnonzero(dp.alive[dp.delta]))
    pos = {int(v): i for i, v in enumerate(keep)}
    out = []
    for s in range(2, dp.delta + 1):
        combos = dp.levels.combos[s]
        # minimal: all subsets feasible (alive), the set itself infeasible
        bad = np.flatnonzero(dp.alive[s] & (dp.costs[s] > budget))
        if s == 2:  # pairs beyond the lower bound are not alive but still conflicts
            bad = np.flatnonzero(dp.costs[s] > budget)
        for r in bad:
            group = [int(v) for v in fr[combos[r]]]
            if all(v in pos for v in group):
                out.append(np.array([pos[v] for v in group]))
    return out
