"""One step of many copies of a team in one compiled call (numba): moves, links, lambda2.

:func:`step_all` does, for every copy, what :class:`tether.envs.episode.Episode` does
for one (without sensing noise): the move of :mod:`tether.envs.plant`, the sensed links
(range by :func:`~tether.graph.kernels.pairs_within_kernel`, line of sight on the grid by
:func:`~tether.world.los_kernels.segment_free_kernel`, occlusion by robot bodies by
:func:`~tether.sensing.robots_kernels.occluded_kernel`), components by union-find,
lambda2 of the unweighted Laplacian (LAPACK ``dsyevd`` through ``eigvalsh``; for two or
three robots the exact value, the known spectrum of the path or the triangle), the
bottleneck margin (Kruskal), close pairs, then the task (:mod:`.vector_tasks`), the
observations and the rewards. Python is entered once per step for all copies, so small
teams are not dominated by interpreter overhead.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tether.envs.vector_tasks import observe_copy, task_copy
from tether.envs.vector_world import point_free, segment_clear
from tether.graph.kernels import sq_dist
from tether.sensing.robots_kernels import occluded_kernel

#: term indices (the order of tether.envs.options.TERMS)
PROGRESS, TARGETS, CONNECTED, DISCONNECTED, LAMBDA2, MARGIN, BASE, COLLISIONS = range(8)
BLOCKED, CLEARANCE = 8, 9
N_TERMS = 10


@njit(cache=True)
def move_copy(q, v, a, step_m, dt, world, start, disp, end):  # noqa: ANN001, ANN201, PLR0913
    """Bound, move and stop one copy's robots (tether.envs.plant.move); returns blocked.

    ``start``, ``disp`` and ``end`` are scratch arrays of ``dim`` values."""
    has_grid, free, shape, origin, to_cells, field, has_bounds, bounds, res = world
    n, dim = q.shape
    blocked = 0
    for i in range(n):
        s = 0.0
        for c in range(dim):
            s += a[i, c] * a[i, c]
        norm = math.sqrt(s)
        long = norm > 1.0 + 1e-9
        moving = False
        for c in range(dim):
            start[c] = q[i, c]
            disp[c] = (a[i, c] / norm if long else a[i, c]) * step_m
            moving = moving or disp[c] != 0.0
        hit = False
        if moving and (has_grid or has_bounds):
            ok = False
            for _ in range(12):
                for c in range(dim):
                    end[c] = start[c] + disp[c]
                if segment_clear(
                    start, end, has_grid, free, shape, origin, to_cells, field
                ) and point_free(end, has_grid, free, shape, origin, res, has_bounds, bounds):
                    ok = True
                    break
                hit = True
                for c in range(dim):
                    disp[c] *= 0.5
            if not ok:
                for c in range(dim):
                    disp[c] = 0.0
        blocked += hit
        for c in range(dim):
            q[i, c] = start[c] + disp[c]
            v[i, c] = (q[i, c] - start[c]) / dt
    return blocked


@njit(cache=True)
def find_root(parent, x):  # noqa: ANN001, ANN201
    """The root of ``x`` in the union-find forest ``parent`` (path halving)."""
    while parent[x] != x:
        parent[x] = parent[parent[x]]
        x = parent[x]
    return x


@njit(cache=True)
def links_into(q, range_m, body_m, world, pairs, keep):  # noqa: ANN001, ANN201
    """The sensed links of one copy (``tether.sensing.sensed_pairs``) into ``pairs[:m]``;
    returns ``m``. ``pairs`` (``(n (n - 1) / 2, 2)`` int64) and ``keep`` (as many
    booleans) are scratch. Occlusion is tested among all the pairs in range, before line
    of sight removes any, as ``sensed_pairs`` does."""
    has_grid, free, shape, origin, to_cells, field = world[:6]
    n = q.shape[0]
    r2 = range_m * range_m
    m = 0
    for i in range(n):  # pairs_within_kernel's pairs, in its order
        for j in range(i + 1, n):
            if sq_dist(q, i, j) <= r2:
                pairs[m, 0], pairs[m, 1] = i, j
                m += 1
    for p in range(m):
        keep[p] = not has_grid or segment_clear(
            q[pairs[p, 0]], q[pairs[p, 1]], has_grid, free, shape, origin, to_cells, field
        )
    if body_m > 0 and m:
        hidden = occluded_kernel(q, pairs[:m], body_m)
        for p in range(m):
            keep[p] = keep[p] and not hidden[p]
    k = 0
    for p in range(m):
        if keep[p]:
            pairs[k, 0], pairs[k, 1] = pairs[p, 0], pairs[p, 1]
            k += 1
    return k


@njit(cache=True)
def work_arrays(n, dim, width):  # noqa: ANN001, ANN201
    """Scratch of one copy's step, made once per call of :func:`step_all`: the move's
    three points, the links and their flags, the graph's lengths, order and parents,
    and the observation's task vectors, flags, row, neighbours, distances and point."""
    most = max(n * (n - 1) // 2, 1)
    return (
        (np.empty(dim), np.empty(dim), np.empty(dim)),
        (np.empty((most, 2), np.int64), np.empty(most, np.bool_)),
        (np.empty(most), np.empty(most, np.int64), np.empty(n, np.int64)),
        (np.empty((n, dim)), np.empty(n), np.empty(width), np.empty(n, np.int64), np.empty(n),
         np.empty(dim)),
    )  # fmt: skip


#: pairs sorted by insertion up to this many (stable: np.argsort's mergesort order)
INSERTION_MAX = 32


@njit(cache=True)
def _stable_order(length, m, order):  # noqa: ANN001, ANN202
    """``np.argsort(length[:m], kind="mergesort")`` into ``order[:m]``."""
    if m > INSERTION_MAX:
        order[:m] = np.argsort(length[:m], kind="mergesort")
        return
    for p in range(m):
        f = p
        while f > 0 and length[order[f - 1]] > length[p]:
            order[f] = order[f - 1]
            f -= 1
        order[f] = p


@njit(cache=True)
def graph_terms(q, pairs, range_m, collision_m, terms, length, order, parent):  # noqa: ANN001, ANN201, PLR0913
    """Connected, lambda2, bottleneck margin and close pairs of one copy into ``terms``
    (``length``, ``order`` and ``parent`` are scratch)."""
    n, dim = q.shape
    m = len(pairs)
    for p in range(m):
        s = 0.0
        for c in range(dim):
            d = q[pairs[p, 0], c] - q[pairs[p, 1], c]
            s += d * d
        length[p] = math.sqrt(s)
    for i in range(n):
        parent[i] = i
    comps = n
    longest = 0.0
    _stable_order(length, m, order)
    for k in range(m):  # Kruskal: the bottleneck of a spanning tree
        p = order[k]
        a, b = find_root(parent, pairs[p, 0]), find_root(parent, pairs[p, 1])
        if a != b:
            parent[a] = b
            comps -= 1
            longest = length[p]
    connected = comps <= 1
    lam = 0.0
    if connected and n == 2:  # one link: the spectrum of the path P2 is {0, 2}
        lam = 2.0
    elif connected and n == 3:  # the path P3 {0, 1, 3} (two links), the triangle {0, 3, 3}
        lam = 1.0 if m == 2 else 3.0
    elif connected and n >= 2:
        lap = np.zeros((n, n))
        for p in range(m):
            i, j = pairs[p, 0], pairs[p, 1]
            lap[i, j] -= 1.0
            lap[j, i] -= 1.0
            lap[i, i] += 1.0
            lap[j, j] += 1.0
        lam = max(np.linalg.eigvalsh(lap)[1], 0.0)
    terms[CONNECTED] = 1.0 if connected else 0.0
    terms[DISCONNECTED] = 0.0 if connected else 1.0
    terms[LAMBDA2] = lam
    if n <= 1:
        terms[MARGIN] = 1.0
    else:
        terms[MARGIN] = max(1.0 - longest / range_m, 0.0) if connected else 0.0
    close = 0
    if collision_m > 0:  # len(pairs_within_kernel(q, collision_m))
        c2 = collision_m * collision_m
        for i in range(n):
            for j in range(i + 1, n):
                close += sq_dist(q, i, j) <= c2
    terms[COLLISIONS] = close


@njit(cache=True)
def step_all(active, q, v, a, steps, obs, terms, rewards, done, sizes, world, task, weights):  # noqa: ANN001, ANN201, PLR0913
    """One step of every copy (module docstring); arrays are changed in place.

    ``sizes`` = ``(step_m, dt_s, max_speed_mps, range_m, body_m, collision_m, k_slots,
    patch_cells, patch_res_m, max_steps)``; ``done[e]`` is 1 terminated, 2 truncated;
    copies with ``active[e]`` false are left as they are.
    """
    step_m, dt, vmax, range_m, body_m, collision_m = sizes[:6]
    max_steps = int(sizes[9])
    n_copies, n, dim = q.shape
    q_old = np.empty((n, dim))
    moving, linking, graph, seeing = work_arrays(n, dim, obs.shape[2])
    for e in range(n_copies):
        if not active[e]:
            continue
        q_old[:] = q[e]
        blocked = move_copy(q[e], v[e], a[e], step_m, dt, world, *moving)
        steps[e] += 1
        pairs = linking[0][: links_into(q[e], range_m, body_m, world, *linking)]
        terms[e, :] = 0.0
        terms[e, BLOCKED] = blocked
        graph_terms(q[e], pairs, range_m, collision_m, terms[e], *graph)
        finished = task_copy(e, q_old, q[e], steps[e] * dt, task, terms[e], seeing[5])
        observe_copy(e, q[e], v[e], pairs, steps[e] * dt, sizes, world, task, obs[e], *seeing)
        r = 0.0
        for t in range(N_TERMS):
            r += weights[t] * terms[e, t]
        rewards[e] = r
        done[e] = 1 if finished else (2 if steps[e] >= max_steps else 0)


@njit(cache=True)
def observe_some(copies, q, v, steps, obs, sizes, world, task):  # noqa: ANN001, ANN201
    """The observations of the listed copies in their current state (after a reset)."""
    _, n, dim = q.shape
    _, linking, _, seeing = work_arrays(n, dim, obs.shape[2])
    for e in copies:
        pairs = linking[0][: links_into(q[e], sizes[3], sizes[4], world, *linking)]
        t_s = steps[e] * sizes[1]
        observe_copy(e, q[e], v[e], pairs, t_s, sizes, world, task, obs[e], *seeing)
