"""Algorithm 1 ("APX") of Banfi et al., Sec. IV-B, with one shared, lazy Steiner DP.

For every subset ``F`` of at most ``delta`` frontiers that Algorithm 1
examines, it needs the cost of the optimal Steiner tree on ``F + {b}``
(Step 11). Instead of one Dreyfus-Wagner run per subset, all subsets share
rank-indexed DP tables (each subset indexed by its colex rank in the
combinatorial number system, not hashed):

* ``P[S][v]``: cheapest tree spanning ``S + {v}``, kept for ``|S| <= delta-2``;
* ``g[S][u]``: cheapest tree spanning ``S + {u}`` in which ``u`` splits ``S``
  in two (the Dreyfus-Wagner merge), kept for ``|S| = delta-1``;
* the Steiner cost of ``S + {b}`` for ``|S| = delta`` is the minimum over the
  splits ``S = A + C`` of ``min_u d(b,u) + P[A][u] + P[C][u]`` and, for the
  split with ``|A| = 1``, ``min_w g[C][w] + E[a][w]`` where
  ``E[a][w] = min_u d(b,u) + d(a,u) + d(u,w)`` is the 3-terminal tree on
  ``{b, a, w}`` (the Dreyfus-Wagner relaxation of ``P[C]`` moved to the
  other side, so no full vector is ever built for the largest subsets).

The tables are filled *on demand* (:class:`LazySteiner`): a row is computed
the first time a subset examined by Algorithm 1 needs it, so the work follows
the subsets Algorithm 1 reaches, not all ``sum_s C(|F|, s)`` of them. The
subsets themselves are generated lazily too (:mod:`.apx_bands`): in the order of
genNewSubset (decreasing utility, increasing size) band by band of utility,
so the utility bound of Step 10 stops the enumeration as well as the DP.

Costs are hop counts (one robot per vertex, unit edge costs) clipped at
``B + 1``: every value ``<= B`` is exact, anything larger means infeasible.
Before any DP work on a subset the paper's pruning rules run: the distance
lower bound of Step 6 (the largest shortest-path distance between two
vertices of ``F + {b}``) and the closed list of Steps 7 and 13 (a subset
with an infeasible subset is infeasible; since Steiner costs are monotone,
checking the subsets with one frontier fewer suffices). For ``delta >= 3`` the
``E`` rows of every frontier are made first; at the other frontier they are the
costs of all pairs, and a subset with a pair that does not fit the budget is
infeasible for the same reason (the *pair filter*): genNewSubset does not make
such subsets and the DP prunes them before the closed list (the same result with
far fewer subsets; the reference is ``pair_filter=False``, and the tests compare them).
The selection loop is Algorithm 1 itself: the utility test of Step 10, the budget
test of Step 12; then completeConfiguration (Step 20). :class:`SharedSteiner` fills
every table eagerly (all subsets of sizes ``< delta``) for tests and benchmarks.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from functools import lru_cache
from math import comb

import numpy as np

from tether import jit
from tether.recurrent.planning.apx_bands import bands
from tether.recurrent.planning.complete import complete_configuration
from tether.recurrent.planning.problem import Problem
from tether.recurrent.planning.steiner import dreyfus_wagner

CHUNK_ROWS = 2048  # subsets per vectorised block (keeps blocks in cache)
FIRST_BLOCK = 8  # subsets examined by Algorithm 1 before the block size doubles
MAX_TABLE_SUBSETS = 1 << 25
"""The most subsets the rank tables may index, ``sum_{2 <= s < delta} C(|F|, s)`` (12
bytes each, so at most 384 MiB): :func:`apx_delta` lowers ``delta`` below that. With no
cap, ``delta = 30`` in ``recurrent_grass`` (12 robots, 84 frontiers) asked for 34 GiB for
the table of the 7-subsets alone. The paper's ``delta = 4`` stays under it up to 580
frontiers."""


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
    delta_used: int = 0
    """The ``delta`` Algorithm 1 ran with (:func:`apx_delta`; 0 without frontiers)."""
    delta_capped: bool = False
    """True if :data:`MAX_TABLE_SUBSETS` lowered it (not only the budget or ``|F|``)."""


def apx_delta(frontiers: int, budget: int, delta: int) -> tuple[int, bool]:
    """The ``delta`` Algorithm 1 runs with, and whether :data:`MAX_TABLE_SUBSETS` lowered it.

    A subset of more than ``budget`` frontiers is infeasible and there are only
    ``frontiers`` of them, so ``min(delta, budget, frontiers)``; then lowered while the
    rank tables of the sizes below it (:class:`LazySteiner`: ``2 <= s < delta``) would
    index more than :data:`MAX_TABLE_SUBSETS` subsets. Theorem 4.1's bound
    (``upper_bound``) holds for the lowered value.
    """
    d = max(1, min(delta, budget, frontiers))
    capped = d
    while capped > 1 and sum(comb(frontiers, s) for s in range(2, capped)) > MAX_TABLE_SUBSETS:
        capped -= 1
    return capped, capped < d


def _relax(
    g: np.ndarray,
    dist: np.ndarray,
    cap: int,
    graph: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """Dreyfus-Wagner relaxation ``P[s, v] = min_u g[s, u] + d(u, v)``, chunked.

    With the kernels on, the same integers from a compiled loop
    (:mod:`tether.recurrent.planning.apx_kernels`); given ``graph`` (CSR ``indptr,
    indices`` of the unit-cost graph whose hop counts clipped at ``cap`` are ``dist``)
    from breadth-first searches on it.
    """
    if jit.enabled():
        from tether.recurrent.planning.apx_kernels import relax_graph_kernel, relax_kernel

        if graph is not None:
            return relax_graph_kernel(np.ascontiguousarray(g), *graph, int(cap))
        return relax_kernel(np.ascontiguousarray(g), dist, int(cap))
    out = np.empty_like(g)
    step = max(1, (1 << 21) // max(1, dist.size))
    for lo in range(0, len(g), step):
        blk = g[lo : lo + step]
        out[lo : lo + step] = (blk[:, :, None] + dist[None, :, :]).min(axis=1)
    return np.minimum(out, cap, out=out)


class _Ranker:
    """Colex ranks (combinatorial number system) of sorted subsets of ``0..k-1``."""

    def __init__(self, k: int, delta: int) -> None:
        self.k = k
        self.binom = np.array(
            [[comb(i, j) for j in range(delta + 2)] for i in range(k + 1)], dtype=np.int64
        )

    def count(self, s: int) -> int:
        """Number of subsets of size ``s``, ``C(k, s)``."""
        return int(self.binom[self.k, s])

    def rank(self, combos: np.ndarray) -> np.ndarray:
        """Colex rank of sorted subsets (rows): ``sum_j C(c_j, j+1)``."""
        s = combos.shape[1]
        return self.binom[combos, np.arange(1, s + 1)].sum(axis=1)


class _Levels(_Ranker):
    """All subsets of frontier positions ``0..k-1`` by size, in colex-rank order."""

    def __init__(self, k: int, delta: int) -> None:
        super().__init__(k, delta)
        self.combos: dict[int, np.ndarray] = {}
        for s in range(1, delta + 1):
            arr = np.array(list(itertools.combinations(range(k), s)), dtype=np.intp).reshape(-1, s)
            out = np.empty_like(arr)
            out[self.rank(arr)] = arr
            out.setflags(write=False)
            self.combos[s] = out


@lru_cache(maxsize=32)
def _levels(k: int, delta: int) -> _Levels:
    return _Levels(k, delta)


@lru_cache(maxsize=16)
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


class _RowStore:
    """Rows of one rank-indexed DP table, stored only for the ranks computed so far."""

    def __init__(self, count: int, width: int, dtype: type) -> None:
        self.slot = np.full(count, -1, dtype=np.int64)
        self.data = np.empty((0, width), dtype=dtype)
        self.size = 0

    def missing(self, ranks: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Distinct ranks without a row, and the index of their first occurrence."""
        todo = np.flatnonzero(self.slot[ranks] < 0)
        uniq, first = np.unique(ranks[todo], return_index=True)
        return uniq, todo[first]

    def add(self, ranks: np.ndarray, rows: np.ndarray) -> None:
        need = self.size + len(ranks)
        if need > len(self.data):
            shape = (max(need, 2 * len(self.data), 64), self.data.shape[1])
            grown = np.empty(shape, dtype=self.data.dtype)
            grown[: self.size] = self.data[: self.size]
            self.data = grown
        self.data[self.size : need] = rows
        self.slot[ranks] = np.arange(self.size, need)
        self.size = need

    def get(self, ranks: np.ndarray) -> np.ndarray:
        return self.data[self.slot[ranks]]


class LazySteiner:
    """Steiner costs of ``F + {root 0}`` for subsets ``F`` of <= delta frontiers, on demand.

    ``steiner_costs(combos)`` returns the clipped cost of each subset (rows of
    sorted frontier positions, one size per call), ``budget + 1`` if it is
    infeasible or pruned by Step 6 or the closed list. Costs of subsets of
    size ``< delta`` are memoised by rank (the closed list looks them up);
    the DP rows (``P``, ``g``, ``E``) are computed once, when first needed.
    With ``pair_filter`` (and ``delta >= 3``) every ``E`` row is made at once and
    ``pair_ok`` says which pairs of frontiers fit the budget with ``b``; subsets of
    three or more frontiers with a pair that does not are pruned first
    (:meth:`pairs_fit`). The costs are the same either way.
    """

    def __init__(
        self,
        dist: np.ndarray,
        frontiers: np.ndarray,
        budget: int,
        delta: int,
        unit_graph: bool = False,
        pair_filter: bool = True,
    ) -> None:
        self.budget = budget
        self.cap = cap = budget + 1
        self.dtype = np.int16 if 3 * cap < np.iinfo(np.int16).max else np.int32
        self.d = d = np.minimum(dist, cap).astype(self.dtype)
        # unit_graph: dist holds hop counts, so d == 1 are the edges (cap >= 2) and the
        # relaxations may search the graph (apx_kernels.relax_graph_kernel)
        self.graph = None
        if unit_graph and cap >= 2:
            src, dst = np.nonzero(d == 1)
            indptr = np.zeros(d.shape[0] + 1, dtype=np.int64)
            np.cumsum(np.bincount(src, minlength=d.shape[0]), out=indptr[1:])
            self.graph = (indptr, dst.astype(np.int64))
        self.d0 = d[0]
        self.fd = d[frontiers]  # P[{f}][v] = d(f, v)
        self.ff = self.fd[:, frontiers]  # frontier-frontier distances (Step 6)
        k = len(frontiers)
        self.delta = delta = max(1, min(delta, k))
        self.ranker = _Ranker(k, delta)
        self.pmax = max(1, delta - 2)
        n = d.shape[0]
        self.rows = {s: _RowStore(self.ranker.count(s), n, self.dtype) for s in range(2, delta)}
        self.e_rows = _RowStore(k, n, self.dtype)  # E[a], built only for delta >= 3
        self.memo = {s: np.full(self.ranker.count(s), -1, np.int32) for s in range(2, delta)}
        self.evaluated = 0
        # pairs of frontiers whose tree with b fits the budget, from the E rows (the
        # 3-terminal trees on {b, a, w}) at the other frontier; kept for delta >= 3
        self.pair_ok: np.ndarray | None = None
        if pair_filter and delta >= 3:
            self.pair_ok = self.e_row(np.arange(k))[:, frontiers] <= budget

    # -------------------------------------------------------------- costs

    def steiner_costs(self, combos: np.ndarray) -> np.ndarray:
        """Clipped Steiner costs of ``F + {b}`` for the subsets ``F`` (rows of ``combos``)."""
        s = combos.shape[1]
        if s == 1:
            return np.minimum(self.fd[combos[:, 0], 0], self.cap).astype(np.int32)
        if s == self.delta:
            return self._evaluate(combos)
        ranks = self.ranker.rank(combos)
        memo = self.memo[s]
        todo = np.flatnonzero(memo[ranks] < 0)
        if len(todo):
            uniq, first = np.unique(ranks[todo], return_index=True)
            memo[uniq] = self._evaluate(combos[todo[first]])
        return memo[ranks]

    def within_lower_bound(self, combos: np.ndarray) -> np.ndarray:
        """Step 6: no two vertices of ``F + {b}`` are more than ``B`` hops apart."""
        ok = self.fd[combos, 0].max(axis=1) <= self.budget
        for i, j in itertools.combinations(range(combos.shape[1]), 2):
            ok &= self.ff[combos[:, i], combos[:, j]] <= self.budget
        return ok

    def closed_list_ok(self, combos: np.ndarray) -> np.ndarray:
        """Steps 7 and 13: every subset with one frontier fewer is feasible."""
        ok = np.ones(len(combos), dtype=bool)
        if combos.shape[1] <= 2:  # singletons are covered by Step 6
            return ok
        for j in range(combos.shape[1]):
            idx = np.flatnonzero(ok)
            sub = np.delete(combos[idx], j, axis=1)
            ok[idx] = self.steiner_costs(sub) <= self.budget
        return ok

    def pairs_fit(self, combos: np.ndarray) -> np.ndarray:
        """Every pair of frontiers of ``F`` has a tree with ``b`` within the budget.

        Steiner costs are monotone (a tree spanning ``F + {b}`` spans every part of
        it), so a subset with a pair that does not fit does not either. Implies Step
        6; a necessary condition of the closed list for ``|F| >= 3``, checked before it
        (the pairs' costs come with the E rows, the closed list's with more DP).
        """
        ok = np.ones(len(combos), dtype=bool)
        for i, j in itertools.combinations(range(combos.shape[1]), 2):
            ok &= self.pair_ok[combos[:, i], combos[:, j]]
        return ok

    def _evaluate(self, combos: np.ndarray) -> np.ndarray:
        """Pruning (Step 6, closed list), then the DP for the survivors."""
        out = np.full(len(combos), self.cap, dtype=np.int32)
        if self.pair_ok is not None and combos.shape[1] >= 3:
            ok = self.pairs_fit(combos)
        else:
            ok = self.within_lower_bound(combos)
        ok[ok] = self.closed_list_ok(combos[ok])
        idx = np.flatnonzero(ok)
        self.evaluated += len(idx)
        for lo in range(0, len(idx), CHUNK_ROWS):
            rows = idx[lo : lo + CHUNK_ROWS]
            out[rows] = self._dp_cost(combos[rows])
        return out

    def _dp_cost(self, c: np.ndarray) -> np.ndarray:
        """Steiner cost of ``S + {b}`` from the DP tables (see the module docstring)."""
        s = c.shape[1]
        if s <= self.pmax:
            cost = self.full(c)[:, 0]
        elif s < self.delta:  # s == delta - 1: the merged table
            cost = (self.merged(c) + self.d0).min(axis=1)
        else:
            cost = np.full(len(c), self.cap, dtype=self.dtype)
            for pa, pc in _splits(s):
                if len(pc) <= self.pmax:
                    val = (self.full(c[:, pa]) + self.full(c[:, pc]) + self.d0).min(axis=1)
                else:  # |A| = 1, |C| = delta - 1
                    val = (self.merged(c[:, pc]) + self.e_row(c[:, pa[0]])).min(axis=1)
                np.minimum(cost, val, out=cost)
        return np.minimum(cost, self.cap).astype(np.int32)

    # -------------------------------------------------------------- tables

    def _merge(self, c: np.ndarray) -> np.ndarray:
        """Dreyfus-Wagner merge ``g[S][u] = min_{S = A + C} P[A][u] + P[C][u]``."""
        best = np.full((len(c), self.d.shape[0]), self.cap, dtype=self.dtype)
        for pa, pc in _splits(c.shape[1]):
            np.minimum(best, self.full(c[:, pa]) + self.full(c[:, pc]), out=best)
        return np.minimum(best, self.cap, out=best)

    def full(self, c: np.ndarray) -> np.ndarray:
        """Rows ``P[S]`` (``|S| <= delta - 2``), computing the missing ones."""
        s = c.shape[1]
        if s == 1:
            return self.fd[c[:, 0]]
        store = self.rows[s]
        ranks = self.ranker.rank(c)
        uniq, first = store.missing(ranks)
        if len(uniq):
            store.add(uniq, _relax(self._merge(c[first]), self.d, self.cap, self.graph))
        return store.get(ranks)

    def merged(self, c: np.ndarray) -> np.ndarray:
        """Rows ``g[S]`` (``|S| = delta - 1``), computing the missing ones."""
        store = self.rows[c.shape[1]]
        ranks = self.ranker.rank(c)
        uniq, first = store.missing(ranks)
        if len(uniq):
            store.add(uniq, self._merge(c[first]))
        return store.get(ranks)

    def e_row(self, a: np.ndarray) -> np.ndarray:
        """Rows ``E[a][w] = min_u d(b,u) + d(a,u) + d(u,w)`` for frontier positions ``a``."""
        uniq, first = self.e_rows.missing(a)
        if len(uniq):
            self.e_rows.add(uniq, _relax(self.fd[uniq] + self.d0, self.d, self.cap, self.graph))
        return self.e_rows.get(a)


class SharedSteiner(LazySteiner):
    """:class:`LazySteiner` filled eagerly, for tests and benchmarks.

    Levels ``1..delta-1`` are computed for every subset on construction; the
    top level ``delta`` (by far the largest) by :meth:`top_costs`. ``costs[s]``
    (indexed by colex rank, as ``levels.combos[s]``) holds ``budget + 1`` for
    infeasible, pruned or not yet computed subsets; ``alive[s]`` marks the
    subsets that pass the closed list and the Step 6 lower bound.
    """

    def __init__(self, dist: np.ndarray, frontiers: np.ndarray, budget: int, delta: int) -> None:
        super().__init__(dist, frontiers, budget, delta)
        self.levels = _levels(len(frontiers), self.delta)
        self.costs: dict[int, np.ndarray] = {}
        self.alive: dict[int, np.ndarray] = {}
        for s, combos in self.levels.combos.items():
            alive = self.within_lower_bound(combos)
            for j in range(s if s > 1 else 0):
                alive &= self.costs[s - 1][self.levels.rank(np.delete(combos, j, axis=1))] <= budget
            self.alive[s] = alive
            if s < self.delta:
                self.costs[s] = self.steiner_costs(combos)
            else:
                self.costs[s] = np.full(len(combos), self.cap, dtype=np.int32)

    def top_costs(self, rows: np.ndarray) -> None:
        """Compute (in place) the costs of the level-``delta`` subsets ``rows``."""
        if len(rows):
            self.costs[self.delta][rows] = self.steiner_costs(self.levels.combos[self.delta][rows])


def solve_apx(problem: Problem, delta: int, pair_filter: bool = True) -> ApxResult:
    """Algorithm 1 with ``delta``, then completeConfiguration (Step 20).

    ``pair_filter``: subsets with a pair of frontiers that does not fit the budget
    are neither made nor costed (:class:`LazySteiner`); they are infeasible, so the
    result is the same as without (the reference, ``False``) but for the work
    counters (``subsets_evaluated``).
    """
    budget = problem.budget
    fr = problem.frontiers
    fr = fr[problem.dist[0, fr] <= budget]
    k = len(fr)
    if k == 0 or budget == 0:
        return ApxResult({0}, 0.0, 0.0, True, 0.0, 0, 0)
    # A subset of more than `budget` frontiers needs more robots than there are: its
    # Steiner tree has at least one vertex per frontier besides b. Enumerating such
    # subsets only feeds the DP infeasible work (C(120, 4) = 8.2 M subsets when 3
    # robots are ready), so the subsets stop at min(delta, budget) frontiers; the
    # result is the same. MAX_TABLE_SUBSETS may lower it further (apx_delta).
    used, capped = apx_delta(k, budget, delta)
    dp = LazySteiner(problem.dist, fr, budget, used, unit_graph=True, pair_filter=pair_filter)
    uf = problem.utility[fr]
    dist_f = np.where(problem.dist > budget, np.inf, problem.dist).astype(float)
    z_best, tree_best, u_best = 0.0, {0}, 0.0
    block = FIRST_BLOCK  # grows across bands: narrow bands do not restart at small blocks
    # subsets with a pair of frontiers that does not fit the budget are infeasible
    # (LazySteiner.pairs_fit): genNewSubset leaves them out; they could only be skipped
    for util, size, combos, lower in bands(uf, dp.delta, dp.ranker.rank, dp.pair_ok):
        pos = 0
        while pos < len(util) and util[pos] > z_best:
            end = pos + int(np.searchsorted(-util[pos : pos + block], -z_best, side="left"))
            block *= 2
            cost = np.empty(end - pos, dtype=np.int32)
            for s in np.unique(size[pos:end]):
                rows = np.flatnonzero(size[pos:end] == s)
                cost[rows] = dp.steiner_costs(combos[pos + rows, :s])
            # the feasible subsets only: Steps 6, 12 and the closed list skip the others
            # (util is non-increasing, so Step 10 stops at the same place)
            for i in (np.flatnonzero(cost <= budget) + pos).tolist():
                if util[i] <= z_best:  # Step 10
                    break
                terminals = [int(v) for v in fr[combos[i, : size[i]]]]  # Step 11
                tree_cost, edges = dreyfus_wagner(dist_f, problem.pred, [*terminals, 0])
                assert tree_cost == cost[i - pos], "shared DP and Dreyfus-Wagner disagree"
                verts = {0, *terminals, *(v for e in edges for v in e)}
                z = float(problem.utility[list(verts)].sum())
                if z > z_best:
                    z_best, tree_best, u_best = z, verts, float(util[i])
            pos = end
        if pos < len(util) or lower <= z_best:  # Step 10 holds for every later subset
            break
    verts = complete_configuration(problem, tree_best)
    utility = float(problem.utility[list(verts)].sum())
    kk = min(budget, k)
    best_possible = float(np.sort(uf)[::-1][:budget].sum())
    # used == min(delta, kk) unless capped, so without the cap these are the paper's
    proven = used >= kk or utility >= best_possible - 1e-12 * max(1.0, best_possible)
    upper = utility if proven else min(best_possible, u_best * kk / used)
    total = sum(dp.ranker.count(s) for s in range(1, dp.delta + 1))
    return ApxResult(verts, utility, u_best, proven, upper, total, dp.evaluated + k, used, capped)
