"""Compiled sensing of :mod:`tether.sensing.robots` (numba): occlusion, CSR, noise.

The kernels, each the arithmetic of its reference, term for term:

* :func:`occluded_kernel` -- :func:`~tether.sensing.robots._occluded`: robot ``j`` hides
  ``k`` from ``i`` when it is closer to both than they are to each other and its body
  meets the segment (Kerestecioglu and Cezayirli, "Connected Navigation of
  Non-Communicating Mobile Agents", Fig. 3); the same squared distances, summed in
  coordinate order, over ``i``'s range-neighbours, robot by robot instead of numpy
  arrays of ``sum_i deg_i^2`` candidates;
* :func:`directed_kernel` -- :func:`~tether.sensing.robots._directed`: both directions
  of every pair sorted by (observer, target) with a counting sort (CSR row pointers and
  targets) and relatives;
* :func:`sense_pairs_kernel` -- for small teams in free space, the three steps before
  the noise in one call (range by :func:`~tether.graph.kernels.pairs_within_kernel`,
  occlusion, CSR): numba's dispatch costs microseconds per call and argument;
* :func:`sense_noisy_kernel` -- for small teams in free space in 2-D, all of
  :func:`~tether.sensing.robots.sense` in one call: :func:`sense_pairs_kernel`, the draws
  of :func:`~tether.sensing.draws_kernels.sensor_errors_kernel`, ``cos``/``sin`` of the
  angular errors and :func:`noise_kernel`; used only where numpy's ``cos``/``sin`` are
  the C library's, which the kernel calls (:func:`numpy_trig_is_libm`);
* :func:`sense_grid_kernel` -- the same on an occupancy grid (range, line of sight,
  CSR; no occlusion), the town and office teams' sensing in one call;
* :func:`noise_kernel` -- the arithmetic of :func:`~tether.sensing.robots._noisy`
  (bounded radial and angular errors, the paper's Fig. 1) once its random numbers are
  drawn: the caller draws them with numpy's ``Generator`` in the reference's order and
  passes them in (with ``cos``/``sin`` of the angular errors, numpy's), so the
  measurements are bit-identical.

Imported only when :func:`tether.sensing.robots._use_kernel` says so (tests compare
each kernel with its reference bit for bit).
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np
from numba import njit

from tether.graph.kernels import pairs_within_kernel
from tether.sensing.draws_kernels import bitgen_addresses, sensor_errors_kernel
from tether.world.los_kernels import segment_free_kernel

EPS = 1e-12  # tether.geometry.unit's default


@njit(cache=True, inline="always")
def _dot_rows(a, i, b, j):  # noqa: ANN001, ANN202
    """``np.einsum("kd,kd->k")`` of rows ``a[i]`` and ``b[j]``, in its summation order.

    numpy's inner loop adds two lanes: ``a_0 b_0 + a_1 b_1`` in 2-D,
    ``(a_0 b_0 + a_2 b_2) + a_1 b_1`` in 3-D (tests compare bit for bit). Rows are
    passed by index: a row view would cost a reference count per call.
    """
    if a.shape[1] == 3:
        return (a[i, 0] * b[j, 0] + a[i, 2] * b[j, 2]) + a[i, 1] * b[j, 1]
    s = 0.0
    for c in range(a.shape[1]):
        s += a[i, c] * b[j, c]
    return s


@njit(cache=True)
def _neighbours(n, pairs):  # noqa: ANN001, ANN202
    """CSR neighbour lists (both directions) of the undirected ``pairs``."""
    indptr = np.zeros(n + 1, np.int64)
    for p in range(len(pairs)):
        indptr[pairs[p, 0] + 1] += 1
        indptr[pairs[p, 1] + 1] += 1
    for v in range(n):
        indptr[v + 1] += indptr[v]
    fill = indptr[:-1].copy()
    nbr = np.empty(indptr[n], np.int64)
    for p in range(len(pairs)):
        a, b = pairs[p, 0], pairs[p, 1]
        nbr[fill[a]] = b
        fill[a] += 1
        nbr[fill[b]] = a
        fill[b] += 1
    return indptr, nbr


@njit(cache=True)
def occluded_kernel(positions, pairs, body_radius_m):  # noqa: ANN001, ANN201
    """Per pair: a third robot's body hides the pair (``_occluded``'s test exactly).

    Each robot's neighbours are sorted by their squared distance (the value the test
    computes), with their relative positions, so the scan of pair ``(i, k)`` stops at the
    first neighbour no closer to ``i`` than ``k``: the test ``|ij|^2 < |ik|^2`` fails for
    every later one. The test's two other conditions are checked one after the other
    (the division of ``perp2`` only where ``|kj|^2 < |ik|^2`` holds): the same booleans.
    """
    n, dim = positions.shape
    m = len(pairs)
    out = np.zeros(m, np.bool_)
    if m == 0 or body_radius_m <= 0:
        return out
    indptr, nbr = _neighbours(n, pairs)
    d2 = np.empty(len(nbr))
    rel = np.empty((len(nbr), dim))  # i -> j, in the sorted order
    w = np.empty((1, dim))
    for i in range(n):
        lo, hi = indptr[i], indptr[i + 1]
        for e in range(lo, hi):  # insertion sort by squared distance (stable)
            j = nbr[e]
            for c in range(dim):
                w[0, c] = positions[j, c] - positions[i, c]
            dj = _dot_rows(w, 0, w, 0)
            f = e
            while f > lo and d2[f - 1] > dj:
                nbr[f], d2[f] = nbr[f - 1], d2[f - 1]
                for c in range(dim):
                    rel[f, c] = rel[f - 1, c]
                f -= 1
            nbr[f], d2[f] = j, dj
            for c in range(dim):
                rel[f, c] = w[0, c]
    r2 = body_radius_m**2
    for p in range(m):
        i, k = pairs[p, 0], pairs[p, 1]
        for c in range(dim):
            w[0, c] = positions[k, c] - positions[i, c]
        d2_ik = _dot_rows(w, 0, w, 0)
        for e in range(indptr[i], indptr[i + 1]):
            d2_ij = d2[e]
            if not d2_ij < d2_ik:
                break
            if nbr[e] == k:
                continue
            proj = _dot_rows(rel, e, w, 0)
            d2_kj = d2_ik - 2.0 * proj + d2_ij
            if d2_kj < d2_ik:
                perp2 = d2_ij - proj * proj / max(d2_ik, 1e-300)
                if perp2 < r2:
                    out[p] = True
                    break
    return out


@njit(cache=True)
def directed_kernel(pairs, positions, n):  # noqa: ANN001, ANN201
    """``_directed`` by a counting sort: CSR indptr, targets (by observer, then target), relatives.

    The directed pair of entry ``e`` is ``(observer, target[e])``, the observer being the
    row of ``indptr`` that holds ``e``.
    """
    m = len(pairs)
    dim = positions.shape[1]
    indptr = np.zeros(n + 1, np.int64)
    for p in range(m):
        indptr[pairs[p, 0] + 1] += 1
        indptr[pairs[p, 1] + 1] += 1
    for v in range(n):
        indptr[v + 1] += indptr[v]
    fill = indptr[:-1].copy()
    target = np.empty(2 * m, np.int64)
    for p in range(m):
        a, b = pairs[p, 0], pairs[p, 1]
        target[fill[a]] = b
        fill[a] += 1
        target[fill[b]] = a
        fill[b] += 1
    rel = np.empty((2 * m, dim))
    for v in range(n):
        lo, hi = indptr[v], indptr[v + 1]
        for e in range(lo + 1, hi):  # insertion sort: lists are short and mostly sorted
            t = target[e]
            f = e
            while f > lo and target[f - 1] > t:
                target[f] = target[f - 1]
                f -= 1
            target[f] = t
        for e in range(lo, hi):
            for c in range(dim):
                rel[e, c] = positions[target[e], c] - positions[v, c]
    return indptr, target, rel


@njit(cache=True)
def sense_pairs_kernel(positions, range_m, body_radius_m):  # noqa: ANN001, ANN201
    """Sensed pairs (no obstacles; occlusion if ``body_radius_m > 0``), then ``_directed``.

    Returns ``(pairs, indptr, target, rel)`` as :func:`~tether.sensing.robots.sense`
    builds them; all pairs are tested (teams of up to a few hundred robots).
    """
    n = positions.shape[0]
    pairs = pairs_within_kernel(positions, range_m)
    if body_radius_m > 0 and len(pairs):
        hidden = occluded_kernel(positions, pairs, body_radius_m)
        keep = 0
        for p in range(len(pairs)):
            if not hidden[p]:
                pairs[keep, 0], pairs[keep, 1] = pairs[p, 0], pairs[p, 1]
                keep += 1
        pairs = pairs[:keep].copy()
    indptr, target, rel = directed_kernel(pairs, positions, n)
    return pairs, indptr, target, rel


@njit(cache=True)
def sense_grid_kernel(positions, range_m, free, shape, origin, to_cells, step_cells, field):  # noqa: ANN001, ANN201, PLR0913
    """Sensed pairs on an occupancy grid (range, then line of sight), then ``_directed``.

    The steps of :func:`~tether.sensing.robots.sensed_pairs` without occlusion in one
    call: :func:`~tether.graph.kernels.pairs_within_kernel`, the segments' ends in cell
    coordinates as :meth:`~tether.world.grid.OccupancyGrid.segments_clear` computes
    them (``(p - origin) * to_cells``), :func:`~tether.world.los_kernels.segment_free_kernel`
    on the raveled free mask ``free`` of ``shape`` (``field``: the distance field or
    empty), the pairs in sight kept in order, and :func:`directed_kernel`.
    """
    n, dim = positions.shape
    pairs = pairs_within_kernel(positions, range_m)
    m = len(pairs)
    if m:
        a = np.empty((m, dim))
        b = np.empty((m, dim))
        for p in range(m):
            for c in range(dim):
                a[p, c] = (positions[pairs[p, 0], c] - origin[c]) * to_cells
                b[p, c] = (positions[pairs[p, 1], c] - origin[c]) * to_cells
        seen = segment_free_kernel(free, shape, a, b, step_cells, field, to_cells)
        keep = 0
        for p in range(m):
            if seen[p]:
                pairs[keep, 0], pairs[keep, 1] = pairs[p, 0], pairs[p, 1]
                keep += 1
        pairs = pairs[:keep].copy()
    indptr, target, rel = directed_kernel(pairs, positions, n)
    return pairs, indptr, target, rel


@njit(cache=True, inline="always")
def _unit_rows(v, i, out, j):  # noqa: ANN001, ANN202
    """``out[j] = unit(v[i])`` as :func:`tether.geometry.unit`; returns ``||v[i]||``."""
    dim = v.shape[1]
    s = 0.0
    for c in range(dim):
        s += v[i, c] * v[i, c]
    norm = math.sqrt(s)
    for c in range(dim):
        out[j, c] = v[i, c] / max(norm, EPS) if norm > EPS else 0.0
    return norm


@njit(cache=True)
def noise_kernel(rel, e_r, cos_a, sin_a, flip, normal):  # noqa: ANN001, ANN201, PLR0913
    """``_noisy``'s measurements from its draws: ``flip`` (2-D) or ``normal`` (3-D).

    2-D: the perpendicular is ``(-u_1, u_0) * sign``, ``sign = (-1, 1)[flip]``
    (``rng.choice([-1, 1])``'s draws: see :mod:`tether.sensing.draws_kernels`); 3-D:
    ``normal`` minus its component along ``u``, normalised (``u x e_x`` when that is
    below 1e-9), as :func:`tether.geometry.random_perpendicular`.
    """
    k, dim = rel.shape
    out = np.empty((k, dim))
    w = np.empty((3, dim))  # rows: u, the perpendicular, its raw direction
    for q in range(k):
        dist = _unit_rows(rel, q, w, 0)
        if dim == 2:
            sign = 1.0 if flip[q] else -1.0
            w[1, 0] = -w[0, 1] * sign
            w[1, 1] = w[0, 0] * sign
        else:
            dot = _dot_rows(normal, q, w, 0)
            for c in range(dim):
                w[2, c] = normal[q, c] - dot * w[0, c]
            s = 0.0
            for c in range(dim):
                s += w[2, c] * w[2, c]
            if math.sqrt(s) < 1e-9:  # np.cross(u, (1, 0, 0))
                w[2, 0] = w[0, 1] * 0.0 - w[0, 2] * 0.0
                w[2, 1] = w[0, 2] * 1.0 - w[0, 0] * 0.0
                w[2, 2] = w[0, 0] * 0.0 - w[0, 1] * 1.0
            _unit_rows(w, 2, w, 1)
        scale = max(dist + e_r[q], 0.0)
        for c in range(dim):
            out[q, c] = (cos_a[q] * w[0, c] + sin_a[q] * w[1, c]) * scale
    return out


@njit(cache=True)
def sense_noisy_kernel(positions, range_m, body_radius_m, noise, radial_m, angular_rad, bitgen):  # noqa: ANN001, ANN201, PLR0913
    """``(pairs, indptr, target, rel, measured)`` of a 2-D team in free space, one call.

    :func:`sense_pairs_kernel`, then the errors drawn as
    :func:`~tether.sensing.draws_kernels.sensor_errors_kernel` draws them (``noise``:
    its codes; ``bitgen``: the bit generator's addresses), ``cos``/``sin`` of the angular
    errors (the C library's: equal to numpy's only where :func:`numpy_trig_is_libm`) and
    :func:`noise_kernel`: the measurements of :func:`~tether.sensing.robots._noisy`.
    """
    pairs, indptr, target, rel = sense_pairs_kernel(positions, range_m, body_radius_m)
    k = len(rel)
    if noise == 0 or k == 0:
        return pairs, indptr, target, rel, rel.copy()
    e_r, e_a, flip = sensor_errors_kernel(k, noise, radial_m, angular_rad, True, bitgen)
    cos_a = np.empty(k)
    sin_a = np.empty(k)
    for q in range(k):
        cos_a[q] = math.cos(e_a[q])
        sin_a[q] = math.sin(e_a[q])
    measured = noise_kernel(rel, e_r, cos_a, sin_a, flip, np.empty((0, 2)))
    return pairs, indptr, target, rel, measured


@njit(cache=True)
def _cos_sin_kernel(x):  # noqa: ANN001, ANN202
    """``cos`` and ``sin`` of ``x`` as the kernels compute them (the C library's)."""
    c = np.empty(len(x))
    s = np.empty(len(x))
    for q in range(len(x)):
        c[q] = math.cos(x[q])
        s[q] = math.sin(x[q])
    return c, s


@cache
def numpy_trig_is_libm() -> bool:
    """numpy's float64 ``cos``/``sin`` give the kernels' (the C library's) values here.

    numpy dispatches them to its own SIMD code on some CPUs (SVML on AVX-512 machines),
    whose last bits differ from the C library's on a good share of arguments; checked
    once per process on 4,096 arguments across ``[-pi, pi]`` (angular errors are below
    ``pi / 2``) and on the sensor's own errors' range.
    """
    x = np.concatenate(
        [np.linspace(-np.pi, np.pi, 2048), np.random.default_rng(0).uniform(-0.5, 0.5, 2048)]
    )
    c, s = _cos_sin_kernel(x)
    return bool(np.array_equal(c, np.cos(x)) and np.array_equal(s, np.sin(x)))


def warm_up() -> None:
    """Compile (or load from numba's cache) the kernels for 2-D and 3-D teams."""
    for dim in (2, 3):
        pos = np.eye(3, dim) * 2.0
        pairs = np.array([[0, 1], [0, 2], [1, 2]], np.int64)
        occluded_kernel(pos, pairs, 0.5)
        sense_pairs_kernel(pos, 3.0, 0.5)
        free = np.ones(4**dim, dtype=np.bool_)
        shape = np.full(dim, 4, dtype=np.int64)
        for field in (np.zeros(0), np.ones(4**dim)):
            sense_grid_kernel(pos, 3.0, free, shape, np.full(dim, -1.0), 1.0, 0.5, field)
        _, _, rel = directed_kernel(pairs, pos, 3)
        k = len(rel)
        flips = np.ones(k, np.uint8)
        noise_kernel(rel, np.zeros(k), np.ones(k), np.zeros(k), flips, np.ones((k, dim)))
    bitgen = bitgen_addresses(np.random.default_rng(0))
    for noise in (0, 1, 2):
        sense_noisy_kernel(np.eye(3, 2) * 2.0, 3.0, 0.5, noise, 0.5, 0.1, bitgen)
    numpy_trig_is_libm()
