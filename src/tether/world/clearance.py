"""Clearance of points and segments from an obstacle point set.

The continuous-connectivity paper models obstacles as a point set ``O``; the
line-of-sight clearance of a segment, ``min_(s, o) ||a + s (b - a) - o||``,
decides whether two robots see each other (App. A). :class:`ObstacleIndex`
answers it exactly with a k-d tree, pre-screened by an occupancy grid's
distance field and a cache of bounds from the previous call (the reference search), or
with the compiled kernel of :mod:`tether.world.clearance_kernels` when
:func:`tether.jit.enabled` (the same results, see :meth:`ObstacleIndex.segment_clearance`).
"""

from __future__ import annotations

import weakref
from functools import cache, cached_property
from itertools import chain

import numpy as np
from scipy.spatial import cKDTree

from tether import jit
from tether.world.grid import OccupancyGrid
from tether.world.world import World


def sample_segments(
    a: np.ndarray, b: np.ndarray, max_spacing_m: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Evenly spaced points on segments ``a[k] -> b[k]``, endpoints included.

    Returns the owning segment of every sample, the ``(total, dim)`` samples
    and the ``(k,)`` spacing of each segment (at most ``max_spacing_m``).
    """
    length = np.linalg.norm(b - a, axis=1)
    n_samp = np.ceil(length / max_spacing_m).astype(np.intp) + 1
    seg = np.repeat(np.arange(len(a)), n_samp)
    first = np.repeat(np.cumsum(n_samp) - n_samp, n_samp)
    frac = (np.arange(len(seg)) - first) / np.repeat(np.maximum(n_samp - 1, 1), n_samp)
    return seg, a[seg] + frac[:, None] * (b - a)[seg], length / np.maximum(n_samp - 1, 1)


@cache
@cache
def einsum_order() -> int:
    """1 if ``numpy.einsum("kd,kd->k")`` sums three terms as ``(x0 + x2) + x1``, else 0.

    numpy's summation order for short rows depends on its SIMD build (two-lane
    vectors give this one); the kernels that reproduce an einsum follow it. Computed
    once per process (it is a property of the numpy build).
    """
    x = np.array([[1.0, 2.0**-53, -1.0]])
    return int(np.einsum("kd,kd->k", x, np.ones((1, 3)))[0] != 0.0)


#: :meth:`ObstacleIndex.shared`: one index per live world object
_SHARED: dict[int, tuple[weakref.ref, ObstacleIndex]] = {}


class ObstacleIndex:
    """The obstacle point set ``O`` with a k-d tree, and an optional grid pre-screen.

    Parameters
    ----------
    points
        ``(m, dim)`` obstacle points.
    grid
        If given, every point must lie in an occupied cell of the grid; its
        distance field (centre to nearest occupied centre) then gives a
        rigorous lower bound of segment clearance, which skips the exact
        search for segments far from every obstacle.
    """

    def __init__(self, points: np.ndarray, dim: int, grid: OccupancyGrid | None = None) -> None:
        self.points = np.ascontiguousarray(np.asarray(points, dtype=float).reshape(-1, dim))
        self.dim = dim
        self.grid = grid if len(self.points) else None
        self.tree = cKDTree(self.points) if len(self.points) else None
        # clearance lower bounds of recent segments: sorted keys, bound, endpoints then
        self._cache: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None

    @classmethod
    def shared(cls, world: World) -> ObstacleIndex:
        """:meth:`from_world`, built once per world object and shared by its users.

        Its caches (clearance bounds, the search table) only decide which searches
        can be skipped, never their answers, so any number of users get the same
        clearances as from a fresh index.
        """
        entry = _SHARED.get(id(world))
        if entry is None or entry[0]() is not world:
            entry = (weakref.ref(world), cls.from_world(world))
            _SHARED[id(world)] = entry
            weakref.finalize(world, _SHARED.pop, id(world), None)
        return entry[1]

    @classmethod
    def from_world(cls, world: World) -> ObstacleIndex:
        """Obstacles of a world, with the grid pre-screen when the points lie in occupied cells.

        A point set equal to all occupied cell centres is thinned to the
        surface first (exact for clearance queries, see
        :meth:`~tether.world.grid.OccupancyGrid.surface_points`).
        """
        pts = np.asarray(world.obstacle_points, dtype=float).reshape(-1, world.dim)
        grid = world.grid
        if grid is None or not len(pts) or not bool(np.all(grid.is_occupied(pts))):
            return cls(pts, world.dim, None)
        if len(pts) == int(grid.occupied.sum()):
            pts = grid.surface_points(outside_is_free=True)
        return cls(pts, world.dim, grid)

    @cached_property
    def _centred(self) -> bool:
        """All obstacle points are cell centres (then the grid bound is tighter)."""
        if self.grid is None:
            return False
        centres = self.grid.to_world(self.grid.to_cell(self.points))
        return bool(np.allclose(centres, self.points, rtol=0, atol=1e-9))

    @cached_property
    def _half_diag_m(self) -> float:
        return 0.5 * self.grid.resolution_m * np.sqrt(self.dim) if self.grid is not None else 0.0

    @cached_property
    def _field(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The grid's distance field raveled, its strides (in cells) and its shape."""
        shape = np.asarray(self.grid.shape)
        strides = np.cumprod(np.r_[shape[1:], 1][::-1])[::-1]
        return self.grid.distance_field_m.ravel(), strides.astype(np.intp), shape

    def _field_at(self, pts: np.ndarray) -> np.ndarray:
        """``DF(c(x))`` per point: distance of its cell centre to the nearest occupied one.

        Equal to ``grid.clearance_m`` (0 outside the grid), with one raveled lookup.
        """
        flat, strides, shape = self._field
        cells = np.floor((pts - self.grid.origin_m) / self.grid.resolution_m).astype(np.intp)
        ok = np.all((cells >= 0) & (cells < shape), axis=1)
        return np.where(ok, flat[np.where(ok, cells @ strides, 0)], 0.0)

    def nearest_min(self, points: np.ndarray, below_m: float = np.inf) -> float:
        """``min_k`` distance from ``points[k]`` to ``O``, where it may be below ``below_m``.

        Exactly ``tree.query(points)[0].min()`` whenever that can be below ``below_m``;
        ``inf`` when the distance field proves every point at least ``below_m`` (plus
        1e-9 m for rounding) away, so ``min(below_m, nearest_min(q, below_m))`` always
        equals ``min(below_m, tree.query(q)[0].min())``. Only the points the field does
        not settle are searched (and only out to ``below_m``). ``inf`` without obstacle
        points.
        """
        if self.tree is None:
            return float("inf")
        points = np.asarray(points, dtype=float).reshape(-1, self.dim)
        if self.grid is not None and np.isfinite(below_m):
            margin = (1.0 if self._centred else 2.0) * self._half_diag_m
            if jit.enabled():  # the same test, compiled
                from tether.world.clearance_kernels import field_below_kernel

                flat, strides, shape, origin, res, _ = self._kernel_field
                near = field_below_kernel(np.ascontiguousarray(points), flat, strides, shape,
                                          origin, res, margin, float(below_m))  # fmt: skip
            else:
                near = self._field_at(points) - margin < below_m + 1e-9
            points = points[near]
            if not len(points):
                return float("inf")
        # the bound only turns distances >= below_m into inf: min(below_m, .) is the same
        return float(self.tree.query(points, distance_upper_bound=below_m)[0].min())

    def _lower_bound(
        self, a: np.ndarray, b: np.ndarray, within_m: float | None = None
    ) -> np.ndarray:
        """A lower bound of every segment's clearance from the grid's distance field.

        With ``within_m``, a coarse pass (samples every four cells) settles the
        segments it already puts beyond ``within_m``; only the others are
        sampled every cell. Both passes give valid bounds.
        """
        if within_m is None:
            return self._field_bound(a, b, self.grid.resolution_m)
        bound = self._field_bound(a, b, 4.0 * self.grid.resolution_m)
        fine = np.flatnonzero(bound < within_m)
        if len(fine):
            bound[fine] = np.maximum(
                bound[fine], self._field_bound(a[fine], b[fine], self.grid.resolution_m)
            )
        return bound

    def _field_bound(self, a: np.ndarray, b: np.ndarray, spacing_m: float) -> np.ndarray:
        """The distance-field bound with samples at most ``spacing_m`` apart."""
        seg, pts, spacing = sample_segments(a, b, spacing_m)
        field = np.full(len(a), np.inf)
        np.minimum.at(field, seg, self._field_at(pts))
        # ||x - o|| >= DF(c(x)) - |x - c(x)| - |o - c(o)|: half a cell diagonal for the
        # sample x, another for the obstacle point o unless o is a cell centre; plus half
        # the sample spacing for segment points between samples
        margin = (1.0 if self._centred else 2.0) * self._half_diag_m
        return field - margin - 0.5 * spacing

    def _cached_bound(
        self,
        keys: np.ndarray,
        a: np.ndarray,
        b: np.ndarray,
        cache: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None,
    ) -> np.ndarray:
        """Lower bounds of clearance from the cache (``-inf`` where no entry).

        Clearance is 1-Lipschitz in the endpoints: every point ``(1 - s) a + s b``
        moves by at most ``max(|a - a0|, |b - b0|)``, so a bound ``c0`` of the
        segment ``a0 -> b0`` gives ``c0 - max(|a - a0|, |b - b0|)`` for ``a -> b``.
        Sound whatever the keys (they only choose which old segment to compare).
        """
        out = np.full(len(keys), -np.inf)
        cache = self._cache if cache is None else cache
        if cache is None or not len(cache[0]):
            return out
        ckeys, cbound, ca, cb = cache
        at = np.minimum(np.searchsorted(ckeys, keys), len(ckeys) - 1)
        hit = ckeys[at] == keys
        at = at[hit]
        move = np.maximum(
            np.linalg.norm(a[hit] - ca[at], axis=1), np.linalg.norm(b[hit] - cb[at], axis=1)
        )
        out[hit] = cbound[at] - move
        return out

    def _store(self, keys: np.ndarray, bound: np.ndarray, a: np.ndarray, b: np.ndarray) -> None:
        order = np.argsort(keys, kind="stable")
        self._cache = (keys[order], bound[order], a[order].copy(), b[order].copy())

    #: Cached segments are searched this much beyond the requested radius, so that their
    #: bound stays useful until an endpoint has moved this far. Small on purpose: a
    #: candidate list holds every point within ``d* + 2 slack`` of its segment, so a wide
    #: slack makes long lists that the team's motion voids within a control step anyway
    #: (the results are the same bits at every slack; the Fig. 9 office trials run about
    #: 4x faster at 0.05 m than at 0.25 m, ``benchmarks/bench_fig9_trials.py``).
    cache_slack_m: float = 0.05

    def _cached_clearance(
        self, a: np.ndarray, b: np.ndarray, within_m: float, keys: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`segment_clearance` settling segments from cached bounds first.

        Segments whose bound (:meth:`_cached_bound`) is still ``>= within_m``
        are beyond ``within_m``; the others are searched out to ``within_m +
        cache_slack_m``, which gives each a new bound ``min(d*, within_m +
        cache_slack_m)`` for later calls. Distances at or beyond ``within_m``
        are reported as ``inf``, exactly as the uncached search does.
        """
        k = len(a)
        dist = np.full(k, np.inf)
        param = np.zeros(k)
        closest = np.zeros((k, self.dim))
        cache = self._cache  # one snapshot: another caller may replace it meanwhile
        known = self._cached_bound(keys, a, b, cache)
        todo = np.flatnonzero(known < within_m)
        reach = within_m + self.cache_slack_m
        d, s, o = self._segment_clearance_reference(a[todo], b[todo], reach)
        near = d < within_m
        dist[todo[near]], param[todo[near]], closest[todo[near]] = d[near], s[near], o[near]
        # carried segments keep their old endpoints and bounds; searched ones start afresh
        bound = np.empty(k)
        new_a, new_b = a.copy(), b.copy()
        carried = np.flatnonzero(known >= within_m)
        if len(carried):
            ckeys, cbound, ca, cb = cache
            at = np.searchsorted(ckeys, keys[carried])
            bound[carried], new_a[carried], new_b[carried] = cbound[at], ca[at], cb[at]
        bound[todo] = np.minimum(d, reach)
        self._store(keys, bound, new_a, new_b)
        return dist, param, closest

    def segment_clearance(
        self,
        a: np.ndarray,
        b: np.ndarray,
        within_m: float,
        keys: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Clearance of segments ``a[k] -> b[k]`` from ``O`` where it is below ``within_m``.

        The compiled kernel (:func:`tether.world.clearance_kernels.segments_nearest`)
        runs when :func:`tether.jit.enabled`, else the reference search
        (:meth:`_segment_clearance_reference`); both give the same bits: the
        least distance over all obstacle points, computed with the same
        arithmetic, ties to the lowest point index.

        With ``keys`` (distinct integers naming the segments, e.g. robot pair
        codes), the reference search reuses lower bounds from its previous call
        with keys: a segment whose cached bound minus its endpoints'
        displacement is still ``>= within_m`` is settled without any search
        (see :meth:`_cached_bound`). The result is identical to the uncached
        one. The kernel keeps its own cache (:meth:`segment_clearance_kernel`).

        Returns
        -------
        dist, param, closest
            ``(k,)`` distance (``inf`` where it is ``>= within_m``), ``(k,)``
            parameter ``s*`` of the closest segment point and ``(k, dim)``
            the closest obstacle point (undefined where ``dist`` is ``inf``).
        """
        if jit.enabled():
            return self.segment_clearance_kernel(a, b, within_m, keys)
        return self._segment_clearance_reference(a, b, within_m, keys)

    @cached_property
    def _kernel_tree(self) -> tuple[np.ndarray, ...]:
        """The compiled search's k-d tree (built on first use)."""
        from tether.world import clearance_kernels as ck

        return ck.build_tree(self.points, ck.LEAF_SIZE)

    @cached_property
    def _kernel_field(self) -> tuple:
        """The distance-field bound's arrays for the kernel (an empty field: no grid)."""
        if self.grid is None:
            z = np.zeros(0, dtype=np.int64)
            return np.zeros(0), z, z, np.zeros(self.dim), 1.0, 0.0
        flat, strides, shape = self._field
        margin = (1.0 if self._centred else 2.0) * self._half_diag_m
        origin = self.grid.origin_m.astype(float)
        return (np.ascontiguousarray(flat), strides.astype(np.int64), shape.astype(np.int64),
                origin, float(self.grid.resolution_m), margin)  # fmt: skip

    def segment_clearance_kernel(
        self, a: np.ndarray, b: np.ndarray, within_m: float, keys: np.ndarray | None = None
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`segment_clearance` by the compiled kernel (needs numba).

        With ``keys``, a hash table per key plays the part of the reference's cache
        (:func:`~tether.world.clearance_cache_kernels.segments_nearest_cached`: bounds,
        and candidate lists for the segments nearer than ``within_m``), and a searched
        segment starts from the closest point its key had last time.
        """
        from tether.world import clearance_cache_kernels as cc
        from tether.world import clearance_kernels as ck

        a = np.ascontiguousarray(a, dtype=float).reshape(-1, self.dim)
        b = np.ascontiguousarray(b, dtype=float).reshape(-1, self.dim)
        if self.tree is None or len(a) == 0:
            return np.full(len(a), np.inf), np.zeros(len(a)), np.zeros((len(a), self.dim))
        if keys is None:
            dist, param, which = ck.segments_nearest(
                *self._kernel_tree, a, b, float(within_m), *self._kernel_field, einsum_order(),
            )  # fmt: skip
        else:
            keys = np.ascontiguousarray(keys, dtype=np.int64)
            table = self._kernel_table(len(keys))
            dist, param, which, added = cc.segments_nearest_cached(
                *self._kernel_tree, a, b, float(within_m), keys,
                self.cache_slack_m, *table, *self._kernel_field, einsum_order(),
            )  # fmt: skip
            self._ktable_used += int(added)
        closest = np.zeros((len(a), self.dim))
        hit = which >= 0
        closest[hit] = self.points[which[hit]]
        return dist, param, closest

    _ktable: tuple[np.ndarray, ...] | None = None
    _ktable_used: int = 0

    def kernel_state(self, n_keys: int) -> tuple:
        """What a compiled caller passes to the cached search: points, tree, table, used, field.

        For kernels that run :func:`~tether.world.clearance_cache_kernels.segments_nearest_cached`
        themselves (it needs ``cache_slack_m`` and :func:`einsum_order` too); they
        report the slots they add with :meth:`kernel_added`.
        """
        return (self.points, self._kernel_tree, self._kernel_table(n_keys), self._ktable_used,
                self._kernel_field)  # fmt: skip

    def kernel_added(self, added: int) -> None:
        self._ktable_used += int(added)

    def kernel_grow(self, n_keys: int) -> None:
        """Start an empty table big enough for ``n_keys`` (a kernel found it too full)."""
        self._ktable = None
        self._ktable_used = 0
        self._kernel_table(n_keys)

    #: candidate-list slots of the kernel's table per key slot
    LIST_SLOTS_PER_KEY = 16
    #: at most this many candidate-list entries (8 MB in 3-D); a full pool is emptied and
    #: refilled by the kernel, so a large team only loses the shortcut, not memory
    LIST_SLOTS_MAX = 1 << 18

    def _kernel_table(self, n_keys: int) -> tuple[np.ndarray, ...]:
        """The kernel's cache table, emptied and enlarged when it would be over half full.

        Keys, bounds, segment endpoints, seeds, then the candidate lists: each slot's
        first list entry, count (-1: none) and epoch, the pool of entries, their coordinates
        and the pool's fill and epoch.
        """
        cap = 0 if self._ktable is None else len(self._ktable[0])
        if self._ktable_used + n_keys > cap // 2:
            cap = 64
            while cap < 4 * n_keys:
                cap *= 2
            slots = min(self.LIST_SLOTS_PER_KEY * cap, self.LIST_SLOTS_MAX)
            self._ktable = (np.full(cap, -1, dtype=np.int64), np.zeros(cap),
                            np.zeros((cap, self.dim)), np.zeros((cap, self.dim)),
                            np.full(cap, -1, dtype=np.int64), np.zeros(cap, dtype=np.int64),
                            np.full(cap, -1, dtype=np.int64), np.zeros(cap, dtype=np.int64),
                            np.zeros(slots, dtype=np.int64), np.zeros((slots, self.dim)),
                            np.zeros(2, dtype=np.int64))  # fmt: skip
            self._ktable_used = 0
        return self._ktable

    def _segment_clearance_reference(
        self,
        a: np.ndarray,
        b: np.ndarray,
        within_m: float,
        keys: np.ndarray | None = None,
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The reference search of :meth:`segment_clearance` (k-d tree balls, numpy)."""
        a = np.asarray(a, dtype=float).reshape(-1, self.dim)
        b = np.asarray(b, dtype=float).reshape(-1, self.dim)
        k = len(a)
        dist = np.full(k, np.inf)
        param = np.zeros(k)
        closest = np.zeros((k, self.dim))
        if self.tree is None or k == 0:
            return dist, param, closest
        if keys is not None:
            return self._cached_clearance(a, b, within_m, np.asarray(keys, dtype=np.int64))
        todo = np.arange(k)
        if self.grid is not None:
            todo = todo[self._lower_bound(a, b, within_m) < within_m]
        if len(todo) == 0:
            return dist, param, closest
        ta, tb = a[todo], b[todo]
        # Candidates. Samples x spaced delta <= within_m / 2 along each segment; the
        # nearest obstacle point of each sample bounds the clearance d* from above, so
        # d* <= r_seg = min(within_m, min over its samples). The closest pair (p*, o*)
        # has o* - p* orthogonal to the segment (or p* at an endpoint, a sample), and p*
        # lies within delta / 2 of a sample x: ||x - o*||^2 <= r_seg^2 + (delta / 2)^2.
        # Nearest distances are needed exactly up to that radius (it exceeds within_m).
        seg, samples, spacing = sample_segments(ta, tb, 0.5 * within_m)
        reach = np.sqrt(within_m**2 + (0.5 * spacing) ** 2)[seg] * (1 + 1e-9)
        near_d = np.full(len(samples), np.inf)
        ask = np.ones(len(samples), dtype=bool)
        if self.grid is not None:  # samples the distance field puts beyond their reach
            margin = (1.0 if self._centred else 2.0) * self._half_diag_m
            ask = self._field_at(samples) - margin < reach
        if ask.any():
            near_d[ask] = self.tree.query(samples[ask], distance_upper_bound=reach[ask].max())[0]
        upper = np.full(len(todo), within_m)
        np.minimum.at(upper, seg, near_d)
        radius = np.sqrt(upper**2 + (0.5 * spacing) ** 2)[seg] * (1 + 1e-9)
        use = near_d <= radius  # the other samples have no obstacle point within radius
        seg, samples, radius = seg[use], samples[use], radius[use]
        hits = self.tree.query_ball_point(samples, radius)
        counts = np.fromiter(map(len, hits), dtype=np.intp, count=len(hits))
        if counts.sum() == 0:
            return dist, param, closest
        flat = np.fromiter(chain.from_iterable(hits), dtype=np.intp, count=int(counts.sum()))
        code = np.unique(np.repeat(seg, counts).astype(np.int64) * len(self.points) + flat)
        owner = (code // len(self.points)).astype(np.intp)
        obs = (code % len(self.points)).astype(np.intp)
        sa, sb, o = ta[owner], tb[owner], self.points[obs]
        ab = sb - sa
        denom = np.einsum("kd,kd->k", ab, ab)
        s = np.clip(np.einsum("kd,kd->k", o - sa, ab) / np.where(denom > 0, denom, 1.0), 0, 1)
        d = np.linalg.norm(sa + s[:, None] * ab - o, axis=1)
        order = np.lexsort((d, owner))
        first = order[np.r_[0, np.flatnonzero(np.diff(owner[order])) + 1]]
        rows = todo[owner[first]]
        near = d[first] < within_m
        rows, first = rows[near], first[near]
        dist[rows] = d[first]
        param[rows] = s[first]
        closest[rows] = o[first]
        return dist, param, closest
