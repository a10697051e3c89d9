"""Exact reductions of a Steiner problem in graphs, run before the dynamic programme.

Each test below removes vertices or edges, or fixes edges into the tree, without changing
the optimum: a tree of the reduced graph plus the fixed edges, with every reduced edge
replaced by the input edges it stands for, is a connected subgraph of the input that
spans the terminals and costs what the reduced tree costs plus the fixed edges. The
dynamic programme then runs on the reduced graph, usually far smaller (fewer vertices,
and fewer terminals once terminals are merged), and its ``3^k`` work shrinks with it.
These are the classic degree tests (Duin and Volgenant, "Reduction tests for the Steiner
problem in graphs", Networks 19, 1989; Koch and Martin, "Solving Steiner tree problems
in graphs to optimality", Networks 32, 1998), applied until none applies:

* **non-terminal of degree 1**: it and its edge go (a tree never needs a leaf that is
  not a terminal);
* **non-terminal of degree 2**: its two edges become one, of their summed weight (a
  tree uses both or neither); when the two ends are already joined, the cheaper of the
  two edges stays;
* **terminal of degree 1**: its edge is in every tree; it is fixed and the terminal
  merged into its neighbour, which becomes a terminal;
* **edge of weight 0**: its ends become one vertex (a terminal if either was): a tree
  of the merged graph plus that edge spans the same terminals at the same cost; the
  reduced graph has positive weights only;
* **nearest terminal**: when a terminal's cheapest edge leads to another terminal, some
  optimal tree has it (put it in any optimal tree and drop the other edge at the
  terminal on the cycle it closes, which is not cheaper); fixed, and the two terminals
  merged.

Weights must be non-negative. Tests that need distances (the long-edge and Steiner
distance tests, nearest vertex) are left out: on the SteinLib instances of
``tests/data/steinlib`` they removed little beyond these, for a Dijkstra run per
terminal.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

__all__ = ["Reduction", "reduce_instance"]


class Reduction(NamedTuple):
    """The reduced problem, as :func:`reduce_instance` returns it."""

    size: int
    """Vertices of the reduced graph, numbered ``0 .. size - 1``."""
    us: np.ndarray
    """First end of each reduced edge (int64)."""
    vs: np.ndarray
    """Second end of each reduced edge (int64)."""
    ws: np.ndarray
    """Weight of each reduced edge (float)."""
    paths: list[tuple[int, ...]]
    """Per reduced edge, the indices of the input edges it stands for."""
    terminals: list[int]
    """The reduced graph's terminals (one, when the fixed edges already join them all)."""
    fixed: list[int]
    """Indices of the input edges that every tree of the reduced graph is completed with."""
    fixed_cost: float
    """Their total weight."""


class _Graph:
    """A simple undirected graph under reduction: ``adj[v][x]`` is the id of edge ``(v, x)``
    in ``weight`` and ``path`` (the input edges it stands for)."""

    def __init__(self, n: int, us: Sequence[int], vs: Sequence[int], ws: Sequence[float]):
        self.adj: list[dict[int, int]] = [{} for _ in range(n)]
        self.weight: list[float] = []
        self.path: list[tuple[int, ...]] = []
        for i, (u, v, w) in enumerate(zip(us, vs, ws, strict=True)):
            if u == v:
                continue
            e = self.adj[u].get(v)
            if e is None:
                self._add(u, v, float(w), (i,))
            elif w < self.weight[e]:
                self.weight[e], self.path[e] = float(w), (i,)
        self.fixed: list[int] = []
        self.fixed_cost = 0.0

    def _add(self, u: int, v: int, w: float, path: tuple[int, ...]) -> None:
        self.adj[u][v] = self.adj[v][u] = len(self.weight)
        self.weight.append(w)
        self.path.append(path)

    def join(self, u: int, v: int, w: float, path: tuple[int, ...]) -> None:
        """Add edge ``(u, v)``, or lower the one there to ``w`` (kept when not heavier)."""
        e = self.adj[u].get(v)
        if e is None:
            self._add(u, v, w, path)
        elif w < self.weight[e]:
            self.weight[e], self.path[e] = w, path

    def remove_vertex(self, v: int) -> list[int]:
        """Drop ``v`` and its edges; returns its former neighbours."""
        nbrs = list(self.adj[v])
        for x in nbrs:
            del self.adj[x][v]
        self.adj[v].clear()
        return nbrs

    def contract(self, v: int, x: int) -> list[int]:
        """Fix edge ``(v, x)`` and merge ``v`` into ``x``; returns the touched vertices."""
        e = self.adj[v].pop(x)
        del self.adj[x][v]
        self.fixed.extend(self.path[e])
        self.fixed_cost += self.weight[e]
        touched = [x]
        for y, f in self.adj[v].items():
            del self.adj[y][v]
            g = self.adj[x].get(y)
            if g is None or self.weight[f] < self.weight[g]:
                self.adj[x][y] = self.adj[y][x] = f
            touched.append(y)
        self.adj[v].clear()
        return touched


def _degree_tests(g: _Graph, term: set[int], stack: list[int]) -> None:
    """Degree-1 and degree-2 non-terminals, degree-1 terminals and nearest terminals,
    from the vertices on ``stack`` (and those they touch) until none applies, or until
    one terminal is left."""
    while stack and len(term) > 1:
        v = stack.pop()
        nbrs = g.adj[v]
        d = len(nbrs)
        if d == 0:
            continue
        if v not in term:
            if d == 1:
                stack.extend(g.remove_vertex(v))
            elif d == 2:
                (x, ex), (y, ey) = nbrs.items()
                w, path = g.weight[ex] + g.weight[ey], g.path[ex] + g.path[ey]
                g.remove_vertex(v)
                g.join(x, y, w, path)
                stack.extend((x, y))
            continue
        x = min(nbrs, key=lambda y: g.weight[nbrs[y]])
        if d == 1 or x in term:
            stack.extend(g.contract(v, x))
            term.discard(v)
            term.add(x)


def _contract_zero_edges(g: _Graph, term: set[int]) -> None:
    """Merge the ends of every zero-weight edge (a terminal if either end is one)."""
    stack = list(range(len(g.adj)))
    while stack and len(term) > 1:
        v = stack.pop()
        x = next((y for y, e in g.adj[v].items() if g.weight[e] == 0), None)
        if x is not None:
            g.contract(v, x)
            if v in term:
                term.discard(v)
                term.add(x)
            stack.append(x)


def reduce_instance(
    n: int, us: Sequence[int], vs: Sequence[int], ws: Sequence[float], terminals: Sequence[int]
) -> Reduction:
    """Reduce the Steiner problem on vertices ``0 .. n-1`` with edges ``(us[i], vs[i])``
    of weights ``ws[i] >= 0`` (self-loops and the heavier of parallel edges ignored)
    and distinct ``terminals`` (at least two, all in one connected component).

    Returns
    -------
    Reduction
        The reduced graph (vertices renumbered), its terminals, the fixed input edges and,
        per reduced edge, the input edges it stands for. An optimal tree of the reduced
        graph (empty when it has one terminal) expanded that way, with the fixed edges,
        is an optimal tree of the input.
    """
    g = _Graph(n, us, vs, ws)
    term = set(terminals)
    if 0.0 in g.weight:
        _contract_zero_edges(g, term)
    _degree_tests(g, term, list(range(n)))
    joined = len(term) <= 1  # the fixed edges join every terminal: nothing else matters
    alive = sorted(term) if joined else [v for v in range(n) if g.adj[v] or v in term]
    index = {v: i for i, v in enumerate(alive)}
    ru, rv, rw, paths = [], [], [], []
    for v in [] if joined else alive:
        for x, e in g.adj[v].items():
            if x > v:
                ru.append(index[v])
                rv.append(index[x])
                rw.append(g.weight[e])
                paths.append(g.path[e])
    return Reduction(
        len(alive),
        np.array(ru, dtype=np.int64),
        np.array(rv, dtype=np.int64),
        np.array(rw, dtype=float),
        paths,
        sorted(index[t] for t in term),
        g.fixed,
        g.fixed_cost,
    )
