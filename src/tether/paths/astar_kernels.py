"""Compiled A* on a padded flat grid: the search loop of :func:`tether.paths.astar.astar_grid`.

The same algorithm as the reference (continuous-connectivity paper, Sec. 3.2): the
open list is a binary heap of ``(f, h, i)`` keys compared lexicographically, as
Python's ``heapq`` compares its tuples, so the cells are closed in the same order
and the same path comes out (a heap pops the least key whatever its layout; two
equal keys name the same cell, so either pop does the same). The heuristic is
evaluated lazily per cell with the reference's formula in the reference's order
of operations (the same bits as its vectorised numpy evaluation), instead of for
every cell of the grid up front. Imported only when :func:`tether.jit.enabled`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

_SQRT2 = math.sqrt(2.0)
_SQRT3 = math.sqrt(3.0)


@njit(cache=True, inline="always")
def _less(f: np.ndarray, h: np.ndarray, c: np.ndarray, a: int, b: int) -> bool:  # noqa: ANN202
    """Heap entry ``a`` sorts before ``b``: the tuple order of ``(f, h, i)``."""
    if f[a] != f[b]:
        return f[a] < f[b]
    if h[a] != h[b]:
        return h[a] < h[b]
    return c[a] < c[b]


@njit(cache=True, inline="always")
def _swap(f: np.ndarray, h: np.ndarray, c: np.ndarray, a: int, b: int) -> None:  # noqa: ANN202
    """Exchange heap entries ``a`` and ``b`` of the three parallel arrays."""
    f[a], f[b] = f[b], f[a]
    h[a], h[b] = h[b], h[a]
    c[a], c[b] = c[b], c[a]


@njit(cache=True, inline="always")
def _heuristic_at(  # noqa: ANN202
    cell: int, goal: np.ndarray, strides: np.ndarray, face: bool, euclid: bool
):
    """:func:`tether.paths.astar._heuristic` of one padded flat cell (same arithmetic).

    Scalars, no allocation: ``|delta|`` per axis (``a2`` is 0 in 2-D, which adds
    exact zeros), sorted descending by swaps for the octile formula.
    """
    dim = len(strides)
    a0 = float(abs(cell // strides[0] - goal[0]))
    rest = cell % strides[0]
    if dim == 2:
        a1 = float(abs(rest - goal[1]))
        a2 = 0.0
    else:
        a1 = float(abs(rest // strides[1] - goal[1]))
        a2 = float(abs(rest % strides[1] - goal[2]))
    if euclid:
        return math.sqrt(a0 * a0 + a1 * a1 + a2 * a2) if dim == 3 else math.sqrt(a0 * a0 + a1 * a1)
    if face:
        return a0 + a1 + a2 if dim == 3 else a0 + a1
    if a0 < a1:
        a0, a1 = a1, a0
    if dim == 2:
        return _SQRT2 * a1 + (a0 - a1)
    if a1 < a2:
        a1, a2 = a2, a1
    if a0 < a1:
        a0, a1 = a1, a0
    return _SQRT3 * a2 + _SQRT2 * (a1 - a2) + (a0 - a1)


@njit(cache=True)
def astar_kernel(  # noqa: ANN201, PLR0913
    padded: np.ndarray,
    strides: np.ndarray,
    offsets: np.ndarray,
    costs: np.ndarray,
    s_idx: int,
    g_idx: int,
    goal: np.ndarray,
    face: bool,
    euclid: bool,
):  # noqa: ANN001
    """Flat cells of the least-cost path ``s_idx -> g_idx`` (empty if none).

    ``padded`` is the raveled free mask padded by one blocked cell per side,
    ``strides`` its C strides in cells, ``offsets``/``costs`` the moves in
    :func:`tether.paths.astar.neighbour_offsets` order, ``goal`` the goal's padded
    coordinates. ``O(E log V)`` time, ``O(V)`` memory.
    """
    size = len(padded)
    closed = -math.inf
    g_cost = np.empty(size)
    for k in range(size):
        g_cost[k] = math.inf if padded[k] else closed
    h_cache = np.full(size, np.nan)
    parent = np.full(size, -1, np.int64)
    cap = 1024
    hf = np.empty(cap)
    hh = np.empty(cap)
    hc = np.empty(cap, np.int64)
    h0 = _heuristic_at(s_idx, goal, strides, face, euclid)
    h_cache[s_idx] = h0
    hf[0], hh[0], hc[0] = h0, h0, s_idx
    top = 1
    g_cost[s_idx] = 0.0
    found = False
    while top > 0:
        i = hc[0]  # pop the least key: move the last entry to the root and sift it down
        top -= 1
        hf[0], hh[0], hc[0] = hf[top], hh[top], hc[top]
        pos = 0
        while True:
            left = 2 * pos + 1
            if left >= top:
                break
            best = left
            if left + 1 < top and _less(hf, hh, hc, left + 1, left):
                best = left + 1
            if not _less(hf, hh, hc, best, pos):
                break
            _swap(hf, hh, hc, pos, best)
            pos = best
        gi = g_cost[i]
        if gi == closed:
            continue  # stale entry of a closed cell
        if i == g_idx:
            found = True
            break
        g_cost[i] = closed
        for k in range(len(offsets)):
            n = i + offsets[k]
            ng = gi + costs[k]
            if ng < g_cost[n]:
                g_cost[n] = ng
                parent[n] = i
                hn = h_cache[n]
                if hn != hn:
                    hn = _heuristic_at(n, goal, strides, face, euclid)
                    h_cache[n] = hn
                if top == cap:  # grow the heap
                    cap *= 2
                    hf2, hh2, hc2 = np.empty(cap), np.empty(cap), np.empty(cap, np.int64)
                    hf2[:top], hh2[:top], hc2[:top] = hf[:top], hh[:top], hc[:top]
                    hf, hh, hc = hf2, hh2, hc2
                pos = top  # push: append and sift up
                hf[pos], hh[pos], hc[pos] = ng + hn, hn, n
                top += 1
                while pos > 0:
                    up = (pos - 1) // 2
                    if not _less(hf, hh, hc, pos, up):
                        break
                    _swap(hf, hh, hc, pos, up)
                    pos = up
    if not found:
        return np.empty(0, np.int64)
    length = 1
    k = g_idx
    while k != s_idx:
        k = parent[k]
        length += 1
    chain = np.empty(length, np.int64)
    k = g_idx
    for p in range(length - 1, -1, -1):
        chain[p] = k
        k = parent[k]
    return chain


def warm_up() -> None:
    """Compile (or load from numba's cache) the kernel for 2-D and 3-D grids."""
    for dim in (2, 3):
        strides = np.array([4 ** (dim - 1 - d) for d in range(dim)], dtype=np.int64)
        padded = np.zeros(4**dim, dtype=np.bool_)
        inner = int(strides.sum())
        padded[inner] = padded[inner + 1] = True
        offsets = np.array([1, -1], dtype=np.int64)
        goal = np.ones(dim, dtype=np.int64)
        goal[-1] = 2
        for face, euclid in ((False, False), (True, False), (False, True)):
            astar_kernel(padded, strides, offsets, np.ones(2), inner, inner + 1, goal, face, euclid)
