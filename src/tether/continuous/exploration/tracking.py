"""Paths as dense tables for the control loop: closest point and virtual point, fast.

The traveling force (eq. (3)) needs, at every integrator sub-step and for every
traveler, the closest point ``q_gamma`` of its path (the one with the largest arc
length among ties, Sec. 3.1), the remaining length ``d_gamma`` and the velocity and
acceleration of the virtual point passing there at cruise speed. A
:class:`~tether.paths.bspline.SplinePath` answers these exactly but one call costs
about a millisecond; here a path is sampled once, every ``spacing_m`` of arc length,
into arrays of points, unit tangents ``T = dp/ds`` and ``d2p/ds2`` (curvature times
normal), and the closest points of all travelers are found in one vectorised pass
over the segments between samples (exact for the sampled polyline; the spline is
within ``kappa spacing^2 / 8`` of it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tether import jit
from tether.paths.bspline import SplinePath

DEFAULT_SPACING_M = 0.1
TIE_M = 1e-6  # closest-point distances this close count as ties (largest s wins)


@dataclass(frozen=True)
class TrackedPath:
    """A path sampled by arc length: ``s`` ``(k,)``; ``points``, ``tangent``, ``curvature``."""

    s: np.ndarray
    points: np.ndarray
    tangent: np.ndarray
    curvature: np.ndarray

    @classmethod
    def from_spline(cls, path: SplinePath, spacing_m: float = DEFAULT_SPACING_M) -> TrackedPath:
        n = max(int(np.ceil(path.length_m / spacing_m)), 1) + 1
        s = np.linspace(0.0, path.length_m, n)
        points, tangent, curvature = path.derivatives(s)
        points = np.atleast_2d(points)
        return cls(s, points, np.atleast_2d(tangent), np.atleast_2d(curvature))

    @property
    def length_m(self) -> float:
        return float(self.s[-1])

    @property
    def end(self) -> np.ndarray:
        return self.points[-1]


@dataclass(frozen=True)
class PathState:
    """Closest points and virtual-point motion of several robots on their paths."""

    s_m: np.ndarray  # (r,) arc length of the closest point
    point_m: np.ndarray  # (r, dim) q_gamma
    distance_m: np.ndarray  # (r,) |q - q_gamma|
    remaining_m: np.ndarray  # (r,) d_gamma
    velocity_mps: np.ndarray  # (r, dim) v_gamma(v_cruise, q_gamma)
    acceleration_mps2: np.ndarray  # (r, dim) a_gamma(v_cruise, q_gamma)


class PathSet:
    """The paths of several robots concatenated once, for repeated closest-point queries.

    Built when the set of paths changes (a control step at most); every query
    (:meth:`states`) is then a handful of vectorised operations over the segments.
    """

    def __init__(self, paths: list[TrackedPath]) -> None:
        self.r = len(paths)
        if self.r == 0:
            return
        sizes = np.array([len(p.s) for p in paths])
        pts = np.concatenate([p.points for p in paths])
        s_all = np.concatenate([p.s for p in paths])
        start = np.ones(len(pts), dtype=bool)
        start[np.cumsum(sizes) - 1] = False  # segments j -> j + 1 inside each path
        a = np.flatnonzero(start)
        self.a = a
        self.who = np.repeat(np.arange(self.r), sizes - 1)
        self.first = np.concatenate([[0], np.cumsum(sizes - 1)[:-1]])  # first segment per path
        self.pa = pts[a]
        self.d = pts[a + 1] - pts[a]
        len2 = np.einsum("kd,kd->k", self.d, self.d)
        self.inv_len2 = np.where(len2 > 0, 1.0 / np.where(len2 > 0, len2, 1.0), 0.0)
        self.sa = s_all[a]
        self.ds = s_all[a + 1] - s_all[a]
        tangent = np.concatenate([p.tangent for p in paths])
        curv = np.concatenate([p.curvature for p in paths])
        self.ta, self.dt = tangent[a], tangent[a + 1] - tangent[a]
        self.ka, self.dk = curv[a], curv[a + 1] - curv[a]
        self.lengths = np.array([p.length_m for p in paths])
        self._kernel: tuple[np.ndarray, ...] | None = None  # the kernel's arrays, made once
        # the kernel's last positions and closest points (without the speed)
        self._last: tuple[np.ndarray, tuple[np.ndarray, ...]] | None = None
        self._zeros: np.ndarray | None = None  # the kernel's speeds in :meth:`closest`

    def states(self, q: np.ndarray, v_cruise_mps: np.ndarray | float) -> PathState:
        """Closest point (largest arc length among ties) and virtual point of each robot.

        ``q[k]`` is the position of the robot following path ``k``. The virtual
        point passes at ``q_gamma`` with tangential speed ``v_cruise``: velocity
        ``v T(s)``, acceleration ``v^2 d2p/ds2`` (centripetal; constant speed),
        both zero at the end of the path. Cost ``O(total samples)``.
        """
        dim = q.shape[1]
        if self.r == 0:
            z = np.zeros((0, dim))
            return PathState(np.zeros(0), z, np.zeros(0), np.zeros(0), z, z)
        if jit.enabled():
            return self._states_kernel(q, v_cruise_mps)
        rel = q[self.who] - self.pa
        t = np.clip(np.einsum("kd,kd->k", rel, self.d) * self.inv_len2, 0.0, 1.0)
        off = rel - t[:, None] * self.d  # q - foot
        dist = np.sqrt(np.einsum("kd,kd->k", off, off))
        best = np.minimum.reduceat(dist, self.first)
        s_foot = self.sa + t * self.ds
        masked = np.where(dist <= best[self.who] + TIE_M, s_foot, -np.inf)
        s_best = np.maximum.reduceat(masked, self.first)
        hit = np.flatnonzero(masked == s_best[self.who])
        pick = hit[np.r_[True, self.who[hit][1:] != self.who[hit][:-1]]]  # first per path
        frac = t[pick][:, None]
        tan = self.ta[pick] + frac * self.dt[pick]
        kap = self.ka[pick] + frac * self.dk[pick]
        speed = np.broadcast_to(np.asarray(v_cruise_mps, dtype=float), (self.r,))
        speed = speed * ((self.lengths - s_best) > 1e-9)
        return PathState(
            s_m=s_best,
            point_m=q - off[pick],
            distance_m=dist[pick],
            remaining_m=np.maximum(self.lengths - s_best, 0.0),
            velocity_mps=speed[:, None] * tan,
            acceleration_mps2=(speed**2)[:, None] * kap,
        )

    def kernel_args(self) -> tuple[np.ndarray, ...]:
        """The arrays
        :func:`~tether.continuous.exploration.tracking_kernels.path_states_kernel` reads.

        Segment ranges per path, the segment arrays, cumulative chord lengths (for its
        skipping) and each path's last closest segment (a hint it updates); made once.
        """
        if self._kernel is None:
            bounds = np.r_[self.first, len(self.a)].astype(np.int64)
            chord = np.sqrt(np.einsum("kd,kd->k", self.d, self.d))
            end = np.cumsum(chord)
            start = end - chord
            offset = np.repeat(start[self.first], np.diff(bounds))  # each path from 0
            self._kernel = (bounds, self.pa, self.d, self.inv_len2, self.sa, self.ds, self.ta,
                            self.dt, self.ka, self.dk, self.lengths, start - offset,
                            end - offset, np.full(self.r, -1))  # fmt: skip
        return self._kernel

    def closest(self, q: np.ndarray) -> tuple[np.ndarray, ...]:
        """``(s, point, distance, remaining, tangent, d2p/ds2)`` at the closest points.

        The speed-free part of :meth:`states`, by
        :func:`~tether.continuous.exploration.tracking_kernels.path_states_kernel` (same bits); the
        last positions' answer is kept, so asking again for the same ``q`` (the roles,
        then the election) costs a comparison.
        """
        q = np.ascontiguousarray(q, dtype=float)
        last = self._last
        if last is not None and last[0].shape == q.shape and (last[0] == q).all():
            return last[1]
        from tether.continuous.exploration.tracking_kernels import path_states_kernel
        from tether.world.clearance import einsum_order

        args = self.kernel_args()
        if self._zeros is None:
            self._zeros = np.zeros(self.r)
        out = path_states_kernel(q, *args[:11], self._zeros, TIE_M, einsum_order(),
                                 *args[11:])  # fmt: skip
        self._last = (q.copy(), out[:4] + out[6:])
        return self._last[1]

    def _states_kernel(self, q: np.ndarray, v_cruise_mps: np.ndarray | float) -> PathState:
        """:meth:`states` by
        :func:`tether.continuous.exploration.tracking_kernels.path_states_kernel` (same
        bits)."""
        s_best, point, dist, remaining, tan, kap = self.closest(q)
        # velocity and acceleration in the kernel's arithmetic: v T and v^2 d2p/ds2
        v = np.asarray(v_cruise_mps, dtype=float) * ((self.lengths - s_best) > 1e-9)
        return PathState(s_best, point, dist, remaining, v[:, None] * tan,
                         (v * v)[:, None] * kap)  # fmt: skip


def path_states(
    paths: list[TrackedPath], q: np.ndarray, v_cruise_mps: np.ndarray | float
) -> PathState:
    """:meth:`PathSet.states` for a one-off query (builds the set each call)."""
    return PathSet(paths).states(q, v_cruise_mps)
