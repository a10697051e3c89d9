"""The teams of many copies placed in one compiled call (numba), each as ``tether run`` does.

:func:`place_all` places copy ``k`` from ``seeds[k]`` exactly as
:func:`tether.runner.place_team` places the team of ``np.random.default_rng(seeds[k])``:
the same draws (:mod:`.vector_random` computes numpy's stream from the seed) through the
same steps, so the same positions to the last bit. Two kinds of ``team.init`` are
compiled:

* ``random_connected`` (:func:`tether.team.random_connected`): the batches of
  candidates (anchors by ``integers``, directions by ``normal``, radii by ``uniform``),
  free space, ``min_separation_m`` from the placed robots (the k-d tree's nearest
  distance, here every placed robot), the clear segment to the anchor, the first-come
  rule within a batch in the same rounds (:func:`tether.team._first_come`), the
  retired anchors and the batch sizes;
* ``uniform`` (:func:`tether.team.uniform_connected`): boxes drawn by ``random`` until
  the team is free, apart and connected within the range.

The team must then be connected in the sensing graph without occlusion (range, and line
of sight when the world has obstacles), as :func:`tether.runner.place_team` checks.
``ok[k]`` is false where the placement or that check fails: the caller places those
copies in Python, which raises the error ``tether run`` gives. The world tuple is that of
:func:`tether.envs.vector_start.world_tuple` with the grid kept even without obstacles
(``World.points_free`` refuses points off the grid), plus whether links need a clear line
of sight.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tether.envs.vector_kernels import find_root
from tether.envs.vector_random import (
    STATE_WORDS,
    bounded,
    next_double,
    seed_state,
    standard_normal,
)
from tether.envs.vector_world import point_free, segment_clear

RANDOM_CONNECTED, UNIFORM = 1, 2
#: rounds of the first-come rule within a batch (tether.team._first_come's default)
ROUNDS = 12


@njit(cache=True)
def _sq(a, b):  # noqa: ANN001, ANN202
    s = 0.0
    for c in range(len(a)):
        d = a[c] - b[c]
        s += d * d
    return s


@njit(cache=True)
def connected(q, range_m, los, world):  # noqa: ANN001, ANN201
    """The team is connected by links within ``range_m`` (clear, if ``los``)."""
    has_grid, free, shape, origin, to_cells, field = world[:6]
    n = len(q)
    parent = np.arange(n)
    comps = n
    r2 = range_m * range_m
    for i in range(n):
        for j in range(i + 1, n):
            if _sq(q[i], q[j]) > r2:
                continue
            if los and not segment_clear(
                q[i], q[j], has_grid, free, shape, origin, to_cells, field
            ):
                continue
            a, b = find_root(parent, i), find_root(parent, j)
            if a != b:
                parent[a] = b
                comps -= 1
    return comps <= 1


@njit(cache=True)
def _first_come(cand, idx, k, sep2, state):  # noqa: ANN001, ANN202
    """``tether.team._first_come`` on the ``k`` candidates ``cand[idx[:k]]``: ``state`` 1
    kept, -1 refused, 0 undecided; returns the first undecided (``k`` if none)."""
    m = 0
    for a in range(k):
        for b in range(a + 1, k):
            m += _sq(cand[idx[a]], cand[idx[b]]) <= sep2
    first, second = np.empty(m, np.int64), np.empty(m, np.int64)
    m = 0
    for a in range(k):
        for b in range(a + 1, k):
            if _sq(cand[idx[a]], cand[idx[b]]) <= sep2:
                first[m], second[m] = a, b
                m += 1
    state[:k] = 1
    for p in range(m):
        state[second[p]] = 0
    blocked = np.zeros(k, np.bool_)
    waiting = np.zeros(k, np.bool_)
    for _ in range(ROUNDS):
        open_ = False
        for j in range(k):
            open_ = open_ or state[j] == 0
        if not open_:
            break
        blocked[:] = False
        waiting[:] = False
        for p in range(m):
            if state[first[p]] == 1:
                blocked[second[p]] = True
            elif state[first[p]] == 0:
                waiting[second[p]] = True
        for j in range(k):
            if state[j] == 0:
                if blocked[j]:
                    state[j] = -1
                elif not waiting[j]:
                    state[j] = 1
    for j in range(k):
        if state[j] == 0:
            return m, j
    return m, k


@njit(cache=True)
def random_connected(st, pos, center, spacing_m, sep_m, max_tries, world):  # noqa: ANN001, ANN201, PLR0912, PLR0915
    """:func:`tether.team.random_connected` into ``pos``; False if it refuses."""
    has_grid, free, shape, origin, to_cells, field, has_bounds, bounds, res = world[:9]
    n, dim = pos.shape
    cap = 4 * n + 16
    anchors = np.empty(cap, np.int64)
    cand = np.empty((cap, dim))
    ok = np.empty(cap, np.bool_)
    idx = np.empty(cap, np.int64)
    state = np.empty(cap, np.int64)
    live = np.empty(n, np.int64)
    fails = np.zeros(n, np.int64)
    alive = np.zeros(n, np.bool_)
    alive[0] = True
    pos[0, :] = center
    count = 1
    rate = 1.0
    reach = np.inf
    sep2 = sep_m * sep_m
    while count < n:
        n_live = 0
        for i in range(count):
            if alive[i]:
                live[n_live] = i
                n_live += 1
        if n_live == 0:
            return False
        limit = min(max(1, count // 32), n - count)
        batch = int(min(max(1.0, 1.2 * limit / rate), 2 * reach, 4.0 * n_live + 16))
        for k in range(batch):
            anchors[k] = live[bounded(st, n_live - 1)]
        for k in range(batch):
            for c in range(dim):
                cand[k, c] = 0.0 + 1.0 * standard_normal(st)  # Generator.normal(0, 1)
        for k in range(batch):
            s = 0.0
            for c in range(dim):
                s += cand[k, c] * cand[k, c]
            norm = math.sqrt(s)
            div = norm if norm > 0 else 1.0
            for c in range(dim):
                cand[k, c] /= div
        for k in range(batch):
            radius = spacing_m * (0.3 + (1.0 - 0.3) * next_double(st))
            for c in range(dim):
                cand[k, c] = pos[anchors[k], c] + radius * cand[k, c]
            ok[k] = point_free(cand[k], has_grid, free, shape, origin, res, has_bounds, bounds)
        if sep_m > 0:
            for k in range(batch):
                if ok[k]:
                    near = np.inf
                    for j in range(count):
                        near = min(near, _sq(cand[k], pos[j]))
                    ok[k] = not (near < sep2 and math.sqrt(near) < sep_m)
        for k in range(batch):
            if ok[k]:
                a = pos[anchors[k]]
                ok[k] = segment_clear(a, cand[k], has_grid, free, shape, origin, to_cells, field)
        tried, reach = batch, np.inf
        k_ok = 0
        for k in range(batch):
            if ok[k]:
                idx[k_ok] = k
                k_ok += 1
        if sep_m > 0 and k_ok > 1:
            m, decided = _first_come(cand, idx, k_ok, sep2, state)
            if m:
                for j in range(k_ok):
                    if state[j] != 1:
                        ok[idx[j]] = False
                if decided < k_ok:
                    tried = idx[decided]
                    reach = float(tried)
                    ok[tried:batch] = False
        n_acc = 0
        for k in range(batch):
            if n_acc < limit and ok[k]:
                pos[count + n_acc, :] = cand[k]
                alive[count + n_acc] = True
                n_acc += 1
                if n_acc == limit:
                    tried = k + 1
        for k in range(tried):
            if not ok[k]:
                fails[anchors[k]] += 1
        for k in range(tried):
            if not ok[k] and fails[anchors[k]] >= max_tries:
                alive[anchors[k]] = False
        count += n_acc
        rate = max(n_acc, 0.5) / tried
    return True


@njit(cache=True)
def uniform_connected(st, pos, center, extent, range_m, sep_m, tries, world):  # noqa: ANN001, ANN201
    """:func:`tether.team.uniform_connected` into ``pos`` (``tries`` draws at most)."""
    has_grid, free, shape, origin, _, _, has_bounds, bounds, res = world[:9]
    n, dim = pos.shape
    sep2 = sep_m * sep_m
    for _ in range(tries):
        for i in range(n):
            for c in range(dim):
                pos[i, c] = center[c] + (next_double(st) - 0.5) * extent[c]
        good = True
        for i in range(n):
            good = good and point_free(
                pos[i], has_grid, free, shape, origin, res, has_bounds, bounds
            )
        if good and sep_m > 0:
            for i in range(n):
                for j in range(i + 1, n):
                    good = good and _sq(pos[i], pos[j]) > sep2
        if good and connected(pos, range_m, False, world):
            return True
    return False


@njit(cache=True)
def place_all(seeds, out, ok, kind, center, size, extent, range_m, sep_m, tries, world, los):  # noqa: ANN001, ANN201, PLR0913
    """Place copy ``k`` of ``out`` (``(copies, n, dim)``) from ``seeds[k]``; ``ok[k]`` as
    in the module docstring. ``kind`` is :data:`RANDOM_CONNECTED` (``size`` the spacing,
    ``tries`` the retirement count) or :data:`UNIFORM` (``extent`` the box, ``tries`` the
    draws); ``range_m`` is the sensing range."""
    st = np.zeros(STATE_WORDS, np.uint64)
    for k in range(len(seeds)):
        seed_state(seeds[k], st)
        if kind == RANDOM_CONNECTED:
            done = random_connected(st, out[k], center, size, sep_m, tries, world)
        else:
            done = uniform_connected(st, out[k], center, extent, range_m, sep_m, tries, world)
        ok[k] = done and connected(out[k], range_m, los, world)
