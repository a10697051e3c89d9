"""Generalized connectivity: weights, potential and the analytic gradient of lambda2.

Continuous-connectivity paper (Nestmeyer et al., "Decentralized simultaneous
multi-target exploration using a connected network of multiple robots"),
Sec. 2 and Appendix A, after Robuffo Giordano et al. (2013).

Weights
-------
For robots ``i != j`` with distance ``d_ij`` and line-of-sight clearance
``d_ijo = min_{s in [0,1], o in O} ||q_i + s (q_j - q_i) - o||``::

    W_ij = A(d_ij) * B(d_ijo) * C_i * C_j                       (App. A, step 2)
    A(d)   = 1 - S(d; R's, Rs)      range factor, 0 iff d >= Rs          (a)
    B(d)   = S(d; Ro, R'o)          obstacle factor, 0 iff d_ijo <= Ro   (b)
    C_i    = prod_{k != i} G(d_ik)  collision factor of robot i          (c)
    G(d)   = S(d; Rc, R'c)          0 iff d <= Rc

so ``W_ij = 0`` exactly when (a) the pair is out of range, (b) its line of
sight comes within ``Ro`` of an obstacle point, or (c) some robot ``k`` is
within ``Rc`` of ``i`` or of ``j``. ``P_ij = A B`` is the *pair factor*.

The smooth step ``S(x; lo, hi)`` is the standard C-infinity transition::

    t = (x - lo) / (hi - lo),   S = 0 for t <= 0,   S = 1 for t >= 1,
    S = 1 / (1 + exp(1/t - 1/(1 - t)))  for 0 < t < 1.

All its derivatives vanish at both ends, so every weight is C-infinity in the
positions (away from switches of the closest obstacle point), it is exactly 0
/ exactly 1 outside the transition band, and ``S(t) + S(1 - t) = 1``.

Potential
---------
``V(l2) = k_V (l_null - l2)^2 / (l2 - l_min)`` for ``l_min < l2 < l_null``,
0 above ``l_null`` and ``+inf`` at or below ``l_min``: zero above
``lambda2_null``, C1 at ``lambda2_null`` and unbounded as lambda2 falls to
``lambda2_min`` (App. A, step 3). The force is eq. (17)::

    f_lambda_i = -dV/dl2 * dlambda2/dq_i.

Gradient
--------
Eq. (18) of the paper (Yang et al. 2010) reads
``dlambda2/dq_i = sum_{j in N_i} dW_ij/dq_i (nu_i - nu_j)^2`` with the unit
Fiedler vector ``nu``. It holds when ``W_ij`` depends only on ``q_i, q_j``;
with the collision factor, ``q_i`` also enters every weight ``W_jk`` of a
robot ``j`` within ``R'c`` of ``i``. The exact gradient
``dlambda2/dq_i = sum_{(j,k)} dW_jk/dq_i (nu_j - nu_k)^2`` then is::

    dlambda2/dq_i = sum_{j in N_i} dP_ij/dq_i C_i C_j (nu_i - nu_j)^2       (pair term, eq. 18)
                  + sum_{k: d_ik < R'c} r(d_ik) u_ik (T_i + T_k)              (collision terms)

with ``u_ik = (q_i - q_k) / d_ik``, ``r = G'/G`` (the log-derivative of the
step, finite and computed without dividing by ``G``) and the *local edge
energy* ``T_i = sum_j W_ij (nu_i - nu_j)^2`` that robot ``j`` can compute and
send. ``dP_ij/dq_i`` contains the range term ``A'(d_ij) u_ij B`` and the
obstacle term ``A B'(d_ijo) (1 - s*) (p* - o*) / d_ijo`` (closest point
``p* = q_i + s* (q_j - q_i)`` on the segment, closest obstacle point ``o*``).
The finite-difference tests check this expression; eq. (18) alone does not
pass them when collision factors are active.

Locality
--------
The *neighbourhood* of robot ``i`` is ``N_i = {j != i : d_ij < Rs}``; because
``R'c < Rs`` (checked) it contains the collision neighbours
``{k : d_ik < R'c}``. Robot ``i``'s gradient is a function of ``q_i``, the
positions of ``N_i``, the obstacle points within ``Rs + R'o`` of ``q_i``,
``nu_i`` and the three scalars ``(nu_j, C_j, T_j)`` that each ``j in N_i``
sends (see :func:`messages` and :func:`lambda2_gradient`). ``C_j`` and
``T_j`` depend on ``j``'s own neighbours, so with messages recomputed from
scratch robot ``i``'s force depends on its 2-hop neighbourhood; with the
messages held fixed it depends only on ``N_i``.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from itertools import chain

import numpy as np
import scipy.linalg
from scipy.spatial import cKDTree
from scipy.special import expit

from tether.graph import pairs_within
from tether.world.grid import OccupancyGrid
from tether.world.world import World


@dataclass(frozen=True)
class ConnectivityParams:
    """The parameters of Table 2 (defaults: empty space and town column).

    Attributes
    ----------
    rs_inner_m, rs_m
        ``(R's, Rs)``: the range factor falls from 1 to 0 between them.
    ro_m, ro_outer_m
        ``(Ro, R'o)``: the obstacle factor rises from 0 to 1 between them.
    rc_m, rc_outer_m
        ``(Rc, R'c)``: the collision factor rises from 0 to 1 between them.
    lambda2_min, lambda2_null
        Where the potential is infinite / becomes zero.
    potential_gain
        ``k_V`` (newtons); the paper does not state it.
    """

    rs_inner_m: float = 2.5
    rs_m: float = 6.0
    ro_m: float = 0.75
    ro_outer_m: float = 1.75
    rc_m: float = 1.0
    rc_outer_m: float = 2.5
    lambda2_min: float = 0.0
    lambda2_null: float = 1.0
    potential_gain: float = 1.0

    def __post_init__(self) -> None:
        if not 0 < self.rs_inner_m < self.rs_m:
            raise ValueError("need 0 < R's < Rs")
        if not 0 < self.ro_m < self.ro_outer_m:
            raise ValueError("need 0 < Ro < R'o")
        if not 0 < self.rc_m < self.rc_outer_m:
            raise ValueError("need 0 < Rc < R'c")
        if not self.rc_outer_m < self.rs_m:
            raise ValueError("need R'c < Rs so that collision neighbours are sensing neighbours")
        if not 0 <= self.lambda2_min < self.lambda2_null:
            raise ValueError("need 0 <= lambda2_min < lambda2_null")
        if not self.potential_gain > 0:
            raise ValueError("potential_gain must be > 0")

    @property
    def transition_width_m(self) -> float:
        """The narrowest of the three transition bands (sets the integrator's step)."""
        return min(
            self.rs_m - self.rs_inner_m, self.ro_outer_m - self.ro_m, self.rc_outer_m - self.rc_m
        )


# --------------------------------------------------------------------------- smooth step


def smooth_step(x: np.ndarray, lo: float, hi: float) -> tuple[np.ndarray, np.ndarray]:
    """``S(x; lo, hi)`` and ``dS/dx`` (see the module docstring)."""
    x = np.asarray(x, dtype=float)
    width = hi - lo
    t = (x - lo) / width
    inside = (t > 0.0) & (t < 1.0)
    tc = np.where(inside, t, 0.5)
    g = 1.0 / tc - 1.0 / (1.0 - tc)
    s_in = expit(-g)
    ds_in = s_in * expit(g) * (1.0 / tc**2 + 1.0 / (1.0 - tc) ** 2) / width
    s = np.where(inside, s_in, (t >= 1.0).astype(float))
    ds = np.where(inside, ds_in, 0.0)
    return s, ds


def smooth_step_log_derivative(x: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """``S'(x) / S(x)`` for ``x > lo`` (0 for ``x <= lo`` and ``x >= hi``), without dividing."""
    x = np.asarray(x, dtype=float)
    width = hi - lo
    t = (x - lo) / width
    inside = (t > 0.0) & (t < 1.0)
    tc = np.where(inside, t, 0.5)
    g = 1.0 / tc - 1.0 / (1.0 - tc)
    r = expit(g) * (1.0 / tc**2 + 1.0 / (1.0 - tc) ** 2) / width
    return np.where(inside, r, 0.0)


# --------------------------------------------------------------------------- potential


def potential(lambda2: float, params: ConnectivityParams) -> tuple[float, float]:
    """``V(lambda2)`` and ``dV/dlambda2`` (``(inf, -inf)`` at or below ``lambda2_min``)."""
    lo, hi, k = params.lambda2_min, params.lambda2_null, params.potential_gain
    if lambda2 >= hi:
        return 0.0, 0.0
    if lambda2 <= lo:
        return float("inf"), float("-inf")
    a = hi - lambda2
    b = lambda2 - lo
    return k * a * a / b, -k * a * (a + 2.0 * b) / (b * b)


def potential_slope(lambda2: np.ndarray, params: ConnectivityParams) -> np.ndarray:
    """Vectorised ``dV/dlambda2`` (huge but finite at or below ``lambda2_min``)."""
    lo, hi, k = params.lambda2_min, params.lambda2_null, params.potential_gain
    lam = np.asarray(lambda2, dtype=float)
    a = np.maximum(hi - lam, 0.0)
    b = np.maximum(lam - lo, 1e-12)
    return -k * a * (a + 2.0 * b) / (b * b)


# --------------------------------------------------------------------------- obstacles


def surface_points(grid: OccupancyGrid) -> np.ndarray:
    """Centres of occupied cells with a free (or outside) face-neighbour.

    For any point outside the obstacles, the nearest occupied cell centre is
    such a surface cell (an interior cell always has a closer occupied
    neighbour towards the point), so the surface replaces the full point set
    in every clearance computation at a fraction of the size. A segment that
    crosses an obstacle enters it through a surface cell, so its clearance is
    below half a cell diagonal with either point set.
    """
    occ = grid.occupied
    padded = np.pad(occ, 1, constant_values=False)
    interior = occ.copy()
    for axis in range(occ.ndim):
        for shift in (-1, 1):
            interior &= np.roll(padded, shift, axis=axis)[(slice(1, -1),) * occ.ndim]
    return grid.to_world(np.argwhere(occ & ~interior)).reshape(-1, occ.ndim)


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
        self.points = np.asarray(points, dtype=float).reshape(-1, dim)
        self.dim = dim
        self.grid = grid if len(self.points) else None
        self.tree = cKDTree(self.points) if len(self.points) else None
        # clearance lower bounds of recent segments: sorted keys, bound, endpoints then
        self._cache: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray] | None = None

    @classmethod
    def from_world(cls, world: World) -> ObstacleIndex:
        """Obstacles of a world, with the grid pre-screen when the points lie in occupied cells.

        A point set equal to all occupied cell centres is thinned to the
        surface first (exact for clearance queries, see :func:`surface_points`).
        """
        pts = np.asarray(world.obstacle_points, dtype=float).reshape(-1, world.dim)
        grid = world.grid
        if grid is None or not len(pts) or not bool(np.all(grid.is_occupied(pts))):
            return cls(pts, world.dim, None)
        if len(pts) == int(grid.occupied.sum()):
            pts = surface_points(grid)
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
    #: bound stays useful until an endpoint has moved this far.
    cache_slack_m: float = 0.25

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
        d, s, o = self.segment_clearance(a[todo], b[todo], reach)
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

        With ``keys`` (distinct integers naming the segments, e.g. robot pair
        codes), lower bounds from the previous call with keys are reused: a
        segment whose cached bound minus its endpoints' displacement is still
        ``>= within_m`` is settled without any search (see
        :meth:`_cached_bound`). The result is identical to the uncached one.

        Returns
        -------
        dist, param, closest
            ``(k,)`` distance (``inf`` where it is ``>= within_m``), ``(k,)``
            parameter ``s*`` of the closest segment point and ``(k, dim)``
            the closest obstacle point (undefined where ``dist`` is ``inf``).
        """
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


# --------------------------------------------------------------------------- weights


@dataclass
class WeightedGraph:
    """Weights of App. A with everything the gradient needs (arrays over pairs).

    ``pairs`` are the ``(m, 2)`` robot pairs within ``Rs`` (``i < j``);
    ``coll_pairs`` the ``(mc, 2)`` pairs within ``R'c``. Per pair:
    ``dP_di``/``dP_dj`` are ``(m, dim)`` derivatives of the pair factor with
    respect to ``q_i``/``q_j``, ``clearance_m`` the line-of-sight clearance
    (``inf`` if beyond ``R'o``). Per collision pair: ``coll_unit`` is
    ``(q_i - q_k) / d_ik`` and ``coll_logd`` the log-derivative ``G'/G``.
    """

    n: int
    pairs: np.ndarray
    pair_factor: np.ndarray
    dP_di: np.ndarray
    dP_dj: np.ndarray
    clearance_m: np.ndarray
    collision: np.ndarray
    coll_pairs: np.ndarray
    coll_unit: np.ndarray
    coll_logd: np.ndarray

    @property
    def weights(self) -> np.ndarray:
        """``W_ij = P_ij C_i C_j`` per pair."""
        return (
            self.pair_factor * self.collision[self.pairs[:, 0]] * self.collision[self.pairs[:, 1]]
        )

    def active(self) -> tuple[np.ndarray, np.ndarray]:
        """Pairs with ``W_ij > 0`` and their weights (the graph ``G_lambda``)."""
        w = self.weights
        keep = w > 0
        return self.pairs[keep], w[keep]

    def laplacian_dense(self) -> np.ndarray:
        """Dense weighted Laplacian ``L = diag(W 1) - W``."""
        lap = np.zeros((self.n, self.n))
        i, j = self.pairs[:, 0], self.pairs[:, 1]
        w = self.weights
        lap[i, j] = -w
        lap[j, i] = -w
        lap[np.diag_indices(self.n)] = -lap.sum(axis=1)
        return lap


def collision_factor(n: int, coll_pairs: np.ndarray, gamma: np.ndarray) -> np.ndarray:
    """``C_i = prod_k G(d_ik)`` per robot from the pair values ``G`` (1 if no pair)."""
    logc = np.zeros(n)
    zero = np.zeros(n, dtype=bool)
    if len(coll_pairs):
        with np.errstate(divide="ignore"):
            lg = np.log(gamma)
        finite = gamma > 0
        np.add.at(logc, coll_pairs[finite, 0], lg[finite])
        np.add.at(logc, coll_pairs[finite, 1], lg[finite])
        zero[coll_pairs[~finite, 0]] = True
        zero[coll_pairs[~finite, 1]] = True
    return np.where(zero, 0.0, np.exp(logc))


def compute_weights(
    positions: np.ndarray,
    params: ConnectivityParams,
    obstacles: ObstacleIndex | None = None,
    pairs: np.ndarray | None = None,
) -> WeightedGraph:
    """The weighted graph ``G_lambda`` of the team (App. A, steps 1-2).

    Parameters
    ----------
    positions
        ``(n, dim)`` robot positions.
    params
        Table 2 parameters.
    obstacles
        Obstacle index (``None``: free space).
    pairs
        Optional precomputed pairs within ``Rs`` (``i < j``); found with a
        k-d tree otherwise.
    """
    q = np.asarray(positions, dtype=float)
    n, dim = q.shape
    if pairs is None:
        pairs = pairs_within(q, params.rs_m)
    pairs = np.asarray(pairs, dtype=np.intp).reshape(-1, 2)
    i, j = pairs[:, 0], pairs[:, 1]
    diff = q[i] - q[j]
    d = np.linalg.norm(diff, axis=1)
    keep = d < params.rs_m
    pairs, i, j, diff, d = pairs[keep], i[keep], j[keep], diff[keep], d[keep]
    u = diff / np.maximum(d, 1e-300)[:, None]
    # A(d) = 1 - S(d) = S(R's + Rs - d) by symmetry; the mirrored form keeps tiny values exact
    a_fac, da = smooth_step(params.rs_inner_m + params.rs_m - d, params.rs_inner_m, params.rs_m)
    da = -da
    dP_di = da[:, None] * u
    clearance = np.full(len(pairs), np.inf)
    b_fac = np.ones(len(pairs))
    if obstacles is not None and len(pairs):
        clearance, s_star, o_star = obstacles.segment_clearance(
            q[i], q[j], params.ro_outer_m, keys=i.astype(np.int64) * n + j
        )
        near = np.isfinite(clearance)
        b_fac, db = smooth_step(
            np.where(near, clearance, params.ro_outer_m), params.ro_m, params.ro_outer_m
        )
        p_star = q[i] + s_star[:, None] * (q[j] - q[i])
        grad_d = (p_star - o_star) / np.maximum(clearance, 1e-300)[:, None]
        grad_d[~near] = 0.0
        dB_di = (db * (1.0 - s_star))[:, None] * grad_d
        dB_dj = (db * s_star)[:, None] * grad_d
        dP_di = dP_di * b_fac[:, None] + a_fac[:, None] * dB_di
        dP_dj = -da[:, None] * u * b_fac[:, None] + a_fac[:, None] * dB_dj
    else:
        dP_dj = -dP_di
    close = d < params.rc_outer_m
    coll_pairs = pairs[close]
    gamma, _ = smooth_step(d[close], params.rc_m, params.rc_outer_m)
    return WeightedGraph(
        n=n,
        pairs=pairs,
        pair_factor=a_fac * b_fac,
        dP_di=dP_di,
        dP_dj=dP_dj,
        clearance_m=clearance,
        collision=collision_factor(n, coll_pairs, gamma),
        coll_pairs=coll_pairs,
        coll_unit=u[close],
        coll_logd=smooth_step_log_derivative(d[close], params.rc_m, params.rc_outer_m),
    )


# --------------------------------------------------------------------------- eigenpair


#: Teams above this size use the sparse solvers (and the warm-started path when given a guess).
SPARSE_MIN_N = 401


def fiedler_pair(
    graph: WeightedGraph, *, guess: np.ndarray | None = None
) -> tuple[float, np.ndarray]:
    """Exact lambda2 and unit Fiedler vector of ``G_lambda``.

    Up to 16 robots the full ``numpy.linalg.eigh``; up to 400 only the second
    eigenpair (``scipy.linalg.eigh`` with ``subset_by_index=[1, 1]``, the
    MRRR driver ``syevr``); above, the certified warm-started inverse
    iteration of :func:`warm_fiedler_pair` when ``guess`` is given, and
    sparse shift-invert Lanczos (:func:`tether.graph.fiedler`) otherwise or
    when the warm path cannot certify its answer.

    ``guess`` (a previous Fiedler vector) fixes the sign of the result, so
    that a warm estimator or a finite-difference test sees a continuous
    vector, and above 400 robots it is the warm start.
    """
    if graph.n < 2:
        return 0.0, np.zeros(graph.n)
    if graph.n >= SPARSE_MIN_N:
        warm = warm_fiedler_pair(graph, guess) if guess is not None else None
        if warm is not None:
            return warm
        from tether.graph import fiedler

        pairs, w = graph.active()
        lam, vec = fiedler(graph.n, pairs, w, method="sparse")
    elif graph.n <= 16:
        vals, vecs = np.linalg.eigh(graph.laplacian_dense())
        lam, vec = max(float(vals[1]), 0.0), vecs[:, 1]
    else:  # only the second eigenpair (LAPACK syevr): 2x faster at 35 robots, 4.5x at 100
        vals, vecs = scipy.linalg.eigh(
            graph.laplacian_dense(), subset_by_index=[1, 1], driver="evr", check_finite=False
        )
        lam, vec = max(float(vals[0]), 0.0), vecs[:, 0]
    if guess is not None and float(vec @ guess) < 0:
        vec = -vec
    return lam, vec


def warm_fiedler_pair(
    graph: WeightedGraph,
    guess: np.ndarray,
    *,
    shift_rel: float = 1e-2,
    tol_rel: float = 1e-10,
    max_iter: int = 12,
    retries: int = 2,
) -> tuple[float, np.ndarray] | None:
    """lambda2 and Fiedler vector by inverse iteration warm-started from ``guess``, certified.

    With ``x0`` the guess made zero-mean and unit, its Rayleigh quotient
    ``theta0 = x0' L x0`` bounds lambda2 from above (Courant-Fischer on the
    complement of the constant vector), so the shift ``tau = theta0 (1 +
    shift_rel)`` lies above lambda2. One sparse ``L D L'`` factorization of
    ``L - tau I`` (SuperLU with a symmetric fill-reducing ordering and
    diagonal pivots) serves twice:

    * its pivots' signs give the inertia (Sylvester's law): exactly two
      negative pivots mean exactly the eigenvalues ``0`` and lambda2 lie
      below ``tau``, so ``lambda3 > tau``;
    * shifted inverse iteration on the complement of the constant vector
      then converges to the Fiedler vector at the rate
      ``(tau - lambda2) / (lambda3 - tau)`` per solve.

    It stops when the Rayleigh quotient ``theta < tau`` and its residual
    ``r = ||L x - theta x||`` satisfy Temple's inequality
    ``theta - lambda2 <= r^2 / (lambda3 - theta) < r^2 / (tau - theta)
    <= tol_rel * theta``; since also ``lambda2 <= theta``, the returned
    ``theta`` is within ``tol_rel`` (relative) of lambda2. With more than two
    negative pivots (``lambda3 < tau``: a small spectral gap or a poor guess)
    the shift moves ten times closer to ``theta0`` up to ``retries`` times.

    Returns
    -------
    (lambda2, vector) or None
        ``None`` when the answer cannot be certified (no factorization,
        wrong inertia, no convergence in ``max_iter`` solves, lambda2 not
        positive); callers then use an exact solver.
    """
    from scipy.sparse import identity
    from scipy.sparse.linalg import splu

    from tether.graph import laplacian

    n = graph.n
    x = np.asarray(guess, dtype=float) - float(np.mean(guess))
    norm = float(np.linalg.norm(x))
    if n < 2 or len(x) != n or not norm > 0:
        return None
    x /= norm
    pairs, w = graph.active()
    lap = laplacian(n, pairs, w).tocsc()
    theta0 = float(x @ (lap @ x))
    if not theta0 > 0:
        return None
    eye = identity(n, format="csc")
    rel = shift_rel
    for _ in range(retries + 1):
        tau = theta0 * (1.0 + rel)
        try:
            lu = splu(
                (lap - tau * eye).tocsc(),
                permc_spec="MMD_AT_PLUS_A",
                diag_pivot_thresh=0.0,
                options={"SymmetricMode": True},
            )
        except RuntimeError:  # exactly singular
            return None
        pivots = lu.U.diagonal()
        if not np.array_equal(lu.perm_r, lu.perm_c) or not np.all(np.isfinite(pivots)):
            return None
        negative = int(np.count_nonzero(pivots < 0))
        if negative == 2:
            break
        if negative < 2:  # impossible in exact arithmetic (0 and lambda2 < tau)
            return None
        rel *= 0.1
    else:
        return None
    v = x
    for _ in range(max_iter):
        y = lu.solve(v)
        y -= y.mean()
        v = y / np.linalg.norm(y)
        lv = lap @ v
        theta = float(v @ lv)
        res = float(np.linalg.norm(lv - theta * v))
        if 0 < theta < tau and res * res <= tol_rel * theta * (tau - theta):
            if float(v @ guess) < 0:
                v = -v
            return theta, v
    return None


# --------------------------------------------------------------------------- gradient


@dataclass
class Messages:
    """What every robot sends its neighbours each step: ``nu_j``, ``C_j``, ``T_j``."""

    nu: np.ndarray
    collision: np.ndarray
    edge_energy: np.ndarray


def edge_energy(graph: WeightedGraph, nu: np.ndarray) -> np.ndarray:
    """``T_i = sum_j W_ij (nu_i - nu_j)^2`` per robot (computable by robot ``i``)."""
    i, j = graph.pairs[:, 0], graph.pairs[:, 1]
    e = graph.weights * (nu[i] - nu[j]) ** 2
    return np.bincount(i, e, graph.n) + np.bincount(j, e, graph.n)


def messages(graph: WeightedGraph, nu: np.ndarray) -> Messages:
    """The per-robot broadcast values at the current configuration."""
    nu = np.asarray(nu, dtype=float)
    return Messages(nu=nu, collision=graph.collision.copy(), edge_energy=edge_energy(graph, nu))


def lambda2_gradient(graph: WeightedGraph, msg: Messages) -> np.ndarray:
    """``dlambda2/dq_i`` for every robot, ``(n, dim)`` (eq. (18) plus collision terms).

    Robot ``i``'s row uses only its own pairs and collision pairs (all inside
    ``N_i``), its own ``C_i``, ``nu_i``, ``T_i`` and its neighbours' messages.
    With ``msg = messages(graph, nu)`` for the exact unit Fiedler vector it is
    the exact gradient of lambda2 (where lambda2 is simple).
    """
    dim = graph.dP_di.shape[1] if graph.dP_di.ndim == 2 else 0
    grad = np.zeros((graph.n, dim))
    i, j = graph.pairs[:, 0], graph.pairs[:, 1]
    cc = msg.collision[i] * msg.collision[j] * (msg.nu[i] - msg.nu[j]) ** 2
    np.add.at(grad, i, graph.dP_di * cc[:, None])  # eq. (18), pair factor
    np.add.at(grad, j, graph.dP_dj * cc[:, None])
    if len(graph.coll_pairs):
        a, b = graph.coll_pairs[:, 0], graph.coll_pairs[:, 1]
        coef = graph.coll_logd * (msg.edge_energy[a] + msg.edge_energy[b])
        term = coef[:, None] * graph.coll_unit  # d d_ab / d q_a = u_ab
        np.add.at(grad, a, term)
        np.add.at(grad, b, -term)
    return grad


def connectivity_force(
    graph: WeightedGraph, lambda2: float | np.ndarray, msg: Messages, params: ConnectivityParams
) -> np.ndarray:
    """``f_lambda_i = -dV/dlambda2 * dlambda2/dq_i`` (eq. (17)), ``(n, dim)``.

    ``lambda2`` may be a scalar or each robot's own estimate ``(n,)``.
    """
    lam = np.broadcast_to(np.asarray(lambda2, dtype=float), (graph.n,))
    return -potential_slope(lam, params)[:, None] * lambda2_gradient(graph, msg)
