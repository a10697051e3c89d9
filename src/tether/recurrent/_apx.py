"""Algorithm 1 ("APX") of Banfi et al., Sec. IV-B, with one shared Steiner DP.

For every subset ``F`` of at most ``delta`` frontiers, Algorithm 1 needs the
cost of the optimal Steiner tree on ``F + {b}`` (Step 11). Instead of one
Dreyfus-Wagner run per subset, the subsets are processed level by level
(size 1, 2, ..., delta) and share their tables, each subset indexed by its
colex rank (combinatorial number system), not hashed:

* ``P[S][v]``: cheapest tree spanning ``S + {v}``, stored for ``|S| <= delta-2``;
* ``g[S][u]``: cheapest tree spanning ``S + {u}`` in which ``u`` splits ``S``
  in two (the Dreyfus-Wagner merge), stored for ``|S| = delta-1``;
* the Steiner cost of ``S + {b}`` for ``|S| = delta`` is the minimum over the
  splits ``S = A + C`` of ``min_u d(b,u) + P[A][u] + P[C][u]`` and, for the
  split with ``|A| = 1``, ``min_w g[C][w] + E[a][w]`` where
  ``E[a][w] = min_u d(b,u) + d(a,u) + d(u,w)`` is the 3-terminal tree on
  ``{b, a, w}`` (the Dreyfus-Wagner relaxation of ``P[C]`` moved to the
  other side, so no full vector is ever built for the largest subsets).

Costs are hop counts (one robot per vertex, unit edge costs) clipped at
``B + 1``: every value ``<= B`` is exact, anything larger means infeasible.
The pruning rules of the paper run before a subset's DP entry is computed:
the closed list (a subset with an infeasible subset is infeasible; since the
levels are processed in increasing size, checking the subsets with one
frontier fewer suffices) and the distance lower bound of Step 6 (the
largest shortest-path distance between two vertices of ``F + {b}``). The
selection loop is Algorithm 1 itself: subsets ranked by decreasing utility
and increasing size, the utility test of Step 10, the budget test of
Step 12; then completeConfiguration (Step 20).
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from functools import lru_cache
from math import comb

import numpy as np

from tether.recurrent._problem import Problem
from tether.recurrent.steiner import _path_edges, dreyfus_wagner

CHUNK_ROWS = 2048  # subsets per vectorised block (keeps blocks in cache)


@dataclass
class ApxResult:
    vertices: set[int]
    """Chosen vertex indices (with the root 0)."""
    utility: float
    best_subset_utility: float
    """``U(F^delta-BEST)``: utility of the best subset of <= delta frontiers."""
    proven_optimal: bool
    upper_bound: float
    subsets_total: int
    subsets_evaluated: int


def _relax(g: np.ndarray, dist: np.ndarray, cap: int) -> np.ndarray:
    """Dreyfus-Wagner relaxation ``P[s, v] = min_u g[s, u] + d(u, v)``, chunked."""
    out = np.empty_like(g)
    step = max(1, (1 << 21) // max(1, dist.size))
    for lo in range(0, len(g), step):
        blk = g[lo : lo + step]
        out[lo : lo + step] = (blk[:, :, None] + dist[None, :, :]).min(axis=1)
    return np.minimum(out, cap, out=out)


class _Levels:
    """Subsets of frontier positions ``0..k-1`` by size, in colex-rank order."""

    def __init__(self, k: int, delta: int) -> None:
        self.k = k
        self.binom = np.array(
            [[comb(i, j) for j in range(delta + 2)] for i in range(k + 1)], dtype=np.int64
        )
        self.combos: dict[int, np.ndarray] = {}
        for s in range(1, delta + 1):
            arr = np.array(list(itertools.combinations(range(k), s)), dtype=np.intp).reshape(-1, s)
            out = np.empty_like(arr)
            out[self.rank(arr)] = arr
            out.setflags(write=False)
            self.combos[s] = out

    def rank(self, combos: np.ndarray) -> np.ndarray:
        """Colex rank of sorted subsets (rows): ``sum_j C(c_j, j+1)``."""
        s = combos.shape[1]
        return self.binom[combos, np.arange(1, s + 1)].sum(axis=1)


@lru_cache(maxsize=32)
def _levels(k: int, delta: int) -> _Levels:
    return _Levels(k, delta)


def _splits(s: int) -> list[tuple[tuple[int, ...], tuple[int, ...]]]:
    """Unordered splits of positions ``0..s-1`` into ``(A, C)``, ``|A| <= |C|``."""
    out = []
    for a in range(1, s // 2 + 1):
        for pos in itertools.combinations(range(s), a):
            if 2 * a == s and 0 not in pos:
                continue
            rest = tuple(i for i in range(s) if i not in pos)
            out.append((pos, rest))
    return out


class SharedSteiner:
    """Steiner costs of ``F + {root 0}`` for subsets ``F`` of <= delta frontiers.

    Levels ``1..delta-1`` are computed on construction; the top level
    ``delta`` (by far the largest) on demand by :meth:`top_costs`, so that
    Algorithm 1 only pays for the subsets it actually examines. ``costs[s]``
    holds ``budget + 1`` for infeasible, pruned or not yet computed subsets;
    ``alive[s]`` marks the subsets that pass the closed list and the Step 6
    lower bound.
    """

    def __init__(self, dist: np.ndarray, frontiers: np.ndarray, budget: int, delta: int) -> None:
        self.budget = budget
        self.cap = cap = budget + 1
        self.d = d = np.minimum(dist, cap).astype(np.int32)
        self.d0 = d[0]
        k = len(frontiers)
        self.delta = delta = max(1, min(delta, k))
        self.levels = levels = _levels(k, delta)
        self.pmax = pmax = max(1, delta - 2)
        self.full: dict[int, np.ndarray] = {}  # P tables (sizes <= pmax)
        self.merged: dict[int, np.ndarray] = {}  # g table (size delta - 1 when > pmax)
        self.costs: dict[int, np.ndarray] = {}
        self.alive: dict[int, np.ndarray] = {}
        self.evaluated = k
        fd = d[frontiers]  # (k, n)
        self.full[1] = fd
        self.costs[1] = fd[:, 0].copy()
        self.alive[1] = self.costs[1] <= budget
        self.e_table: np.ndarray | None = None
        n = d.shape[0]
        for s in range(2, delta + 1):
            combos = levels.combos[s]
            ok = np.ones(len(combos), dtype=bool)
            for j in range(s):  # closed list: all subsets with one frontier fewer feasible
                ok &= self.costs[s - 1][levels.rank(np.delete(combos, j, axis=1))] <= budget
            if s == 2:  # Step 6 lower bound (for s >= 3 the closed list implies it)
                ok &= d[frontiers[combos[:, 0]], frontiers[combos[:, 1]]] <= budget
            self.alive[s] = ok
            self.costs[s] = np.full(len(combos), cap, dtype=np.int32)
            if s == delta:
                if any(len(pc) > pmax for _, pc in _splits(s)):
                    self.e_table = _relax(fd + self.d0[None, :], d, cap)  # E[a][w]
                break
            idx = np.flatnonzero(ok)
            self.evaluated += len(idx)
            g = np.full((len(combos), n), cap, dtype=np.int32)
            for lo in range(0, len(idx), CHUNK_ROWS):
                rows = idx[lo : lo + CHUNK_ROWS]
                c = combos[rows]
                best = np.full((len(rows), n), cap, dtype=np.int32)
                for pa, pc in _splits(s):
                    a = self.full[len(pa)][levels.rank(c[:, pa])]
                    b = self.full[len(pc)][levels.rank(c[:, pc])]
                    np.minimum(best, a + b, out=best)
                g[rows] = np.minimum(best, cap)
            if s <= pmax:
                self.full[s] = _relax(g, d, cap)
                self.costs[s][idx] = self.full[s][idx, 0]
            else:
                self.merged[s] = g
                self.costs[s][idx] = np.minimum((g[idx] + self.d0).min(axis=1), cap)

    def top_costs(self, rows: np.ndarray) -> None:
        """Compute (in place) the costs of the level-``delta`` subsets ``rows``."""
        s = self.delta
        if s == 1 or len(rows) == 0:
            return
        levels, full, pmax = self.levels, self.full, self.pmax
        self.evaluated += len(rows)
        for lo in range(0, len(rows), CHUNK_ROWS):
            blk = rows[lo : lo + CHUNK_ROWS]
            c = levels.combos[s][blk]
            best = np.full(len(blk), self.cap, dtype=np.int32)
            for pa, pc in _splits(s):
                if len(pc) <= pmax:
                    a = full[len(pa)][levels.rank(c[:, pa])]
                    b = full[len(pc)][levels.rank(c[:, pc])]
                    val = (a + b + self.d0).min(axis=1)
                else:  # |A| = 1, |C| = delta - 1
                    gc = self.merged[len(pc)][levels.rank(c[:, pc])]
                    val = (gc + self.e_table[c[:, pa[0]]]).min(axis=1)
                np.minimum(best, val, out=best)
            self.costs[s][blk] = np.minimum(best, self.cap)


def solve_apx(problem: Problem, delta: int) -> ApxResult:
    """Algorithm 1 with ``delta``, then completeConfiguration (Step 20)."""
    budget = problem.budget
    fr = problem.frontiers
    fr = fr[problem.dist[0, fr] <= budget]
    k = len(fr)
    if k == 0 or budget == 0:
        return ApxResult({0}, 0.0, 0.0, True, 0.0, 0, 0)
    dp = SharedSteiner(problem.dist, fr, budget, delta)
    uf = problem.utility[fr]
    top = dp.delta
    util = np.concatenate([uf[c].sum(axis=1) for c in dp.levels.combos.values()])
    size = np.concatenate([np.full(len(c), s) for s, c in dp.levels.combos.items()])
    rank = np.concatenate([np.arange(len(c)) for c in dp.levels.combos.values()])
    alive = np.concatenate([dp.alive[s] for s in dp.levels.combos])
    order = np.lexsort((size, -util))  # genNewSubset: decreasing utility, increasing size
    order = order[alive[order]]  # subsets pruned by the closed list or Step 6
    dist_f = np.where(problem.dist > budget, np.inf, problem.dist).astype(float)
    z_best, tree_best, u_best = 0.0, {0}, 0.0
    lo, block = 0, 256
    done = False
    while lo < len(order) and not done:
        chunk = order[lo : lo + block]
        lo += block
        block *= 2
        if util[chunk[0]] <= z_best:  # Step 10 for this and every later subset
            break
        dp.top_costs(rank[chunk[size[chunk] == top]])
        for i in chunk:
            if util[i] <= z_best:  # Step 10
                done = True
                break
            s, r = int(size[i]), int(rank[i])
            if dp.costs[s][r] > budget:  # Step 12: closed
                continue
            terminals = [int(v) for v in fr[dp.levels.combos[s][r]]]  # Step 11
            cost, edges = dreyfus_wagner(dist_f, problem.pred, [*terminals, 0])
            assert cost == dp.costs[s][r], "shared DP and Dreyfus-Wagner disagree"
            verts = {0, *terminals, *(v for e in edges for v in e)}
            z = float(problem.utility[list(verts)].sum())
            if z > z_best:
                z_best, tree_best, u_best = z, verts, float(util[i])
    verts = complete_configuration(problem, tree_best)
    utility = float(problem.utility[list(verts)].sum())
    kk = min(budget, k)
    best_possible = float(np.sort(uf)[::-1][:budget].sum())
    proven = delta >= kk or utility >= best_possible - 1e-12 * max(1.0, best_possible)
    upper = utility if proven else min(best_possible, u_best * kk / delta)
    return ApxResult(verts, utility, u_best, proven, upper, len(util), dp.evaluated)


def complete_configuration(problem: Problem, tree: set[int]) -> set[int]:
    """Step 20: greedily hang branches to the best still-reachable frontiers.

    While robots remain, connect the unoccupied frontier of highest utility
    among those within the remaining budget (hops from the current tree) by
    a shortest path from its nearest tree vertex.
    """
    verts = set(tree)
    remaining = problem.budget - (len(verts) - 1)
    d = problem.dist
    while remaining > 0:
        members = np.fromiter(verts, dtype=np.intp)
        near = d[members]
        src = members[np.argmin(near, axis=0)]
        gap = near.min(axis=0)
        cand = [
            int(f) for f in problem.frontiers if f not in verts and gap[f] <= remaining
        ]  # frontiers are sorted by decreasing utility
        if not cand:
            break
        f = cand[0]
        for a, b in _path_edges(problem.pred, int(src[f]), f):
            verts.update((a, b))
        remaining = problem.budget - (len(verts) - 1)
    return verts
