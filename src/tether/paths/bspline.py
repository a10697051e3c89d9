"""B-spline paths: smoothing of an A* polyline, arc length, closest point, remaining length.

The continuous-connectivity paper (Nestmeyer et al., Sec. 3.1-3.2) turns the A*
waypoints into a C2 path ``gamma_i`` "approximated with a B-spline (Biagiotti and
Melchiorri 2008) in order to remove corners from the path", and notes that,
"depending on the smoothing parameter, this approximation is not guaranteed to leave
enough clearance from surrounding obstacles". Here the clearance is checked and the
smoothing reduced until it holds (:func:`smooth_path`).

Which spline: FITPACK's parametric smoothing spline (``scipy.interpolate.splprep``,
cubic, so C2) fitted to the polyline densely resampled, with the chord-length
parameter. Its smoothing condition ``sum |c(u_j) - x_j|^2 <= s`` is set from a metric
RMS tolerance (``s = m * tolerance_m**2`` for ``m`` samples), so "less smoothing" has a
meaning in metres, and FITPACK places the knots itself (few knots on straight runs).
``splprep`` rather than ``make_splprep`` because the project supports scipy >= 1.11
(``make_splprep`` appeared in 1.15). The fitted spline is held as one vector-valued
:class:`scipy.interpolate.BSpline`; its clamped end coefficients are set to the exact
start and goal, so the path starts at the robot and ends at the target.

Paths are parametrised by arc length ``s`` (metres) through a dense table (all knots
plus uniform nodes, Gauss-Legendre quadrature of ``|c'(u)|`` on each interval) and
Newton refinement, so ``s`` is accurate to about 1e-10 of the length.
"""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
from scipy import ndimage
from scipy.interpolate import BSpline, splprep

from tether.world.grid import OccupancyGrid
from tether.world.world import World

__all__ = [
    "ClosestPoint",
    "SplinePath",
    "closest_point",
    "needs_replan",
    "remaining_length",
    "smooth_path",
]

_GL_X, _GL_W = np.polynomial.legendre.leggauss(5)
_SHRINK = (1.0, 0.5, 0.25, 0.125, 0.0625)  # tolerance factors tried before the polyline
_LOCAL_ROUNDS = 4  # per tolerance: fits with the weights raised around failures


class SplinePath:
    """A path ``p(s)``, ``s`` in ``[0, length_m]``, given by a vector-valued B-spline.

    Parameters
    ----------
    spline
        :class:`scipy.interpolate.BSpline` with ``(n, dim)`` coefficients on the
        parameter interval ``[0, 1]``; degree 3 (smooth) or 1 (a polyline).
    kind
        ``"spline"`` or ``"polyline"`` (the fallback of :func:`smooth_path`).
    tolerance_m
        RMS smoothing tolerance used for the fit (0 for a polyline).
    """

    def __init__(self, spline: BSpline, kind: str = "spline", tolerance_m: float = 0.0) -> None:
        self.spline = spline
        self.kind = kind
        self.tolerance_m = float(tolerance_m)
        self._d1 = spline.derivative(1)
        self._d2 = spline.derivative(2) if spline.k >= 2 else None
        knots = np.unique(spline.t[(spline.t >= 0.0) & (spline.t <= 1.0)])
        n_uniform = max(256, 16 * (len(knots) - 1))
        u = np.unique(np.concatenate([knots, np.linspace(0.0, 1.0, n_uniform + 1)]))
        seg = self._integrate(u[:-1], u[1:])
        self._u = u
        self._s = np.concatenate([[0.0], np.cumsum(seg)])
        self._pts = self.spline(u)  # dense samples, for closest-point candidates
        self.length_m = float(self._s[-1])

    # ---------------------------------------------------------------- construction

    @classmethod
    def polyline(cls, waypoints_m: np.ndarray) -> SplinePath:
        """The polyline through ``waypoints_m`` (``(k, dim)``) as a degree-1 B-spline."""
        pts = _dedupe(np.atleast_2d(np.asarray(waypoints_m, dtype=float)))
        if len(pts) == 1:
            pts = np.concatenate([pts, pts])
        u = _chord_param(pts)
        knots = np.concatenate([[0.0], u, [1.0]])
        return cls(BSpline(knots, pts, 1), kind="polyline")

    # ---------------------------------------------------------------- arc length

    def _speed_u(self, u: np.ndarray) -> np.ndarray:
        return np.linalg.norm(self._d1(u), axis=-1)

    def _integrate(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """``int_a^b |c'(u)| du`` by 5-point Gauss-Legendre, elementwise."""
        half = 0.5 * (b - a)
        mid = 0.5 * (b + a)
        nodes = mid[..., None] + half[..., None] * _GL_X
        return half * (self._speed_u(nodes.ravel()).reshape(nodes.shape) @ _GL_W)

    def arc_length(self, u: np.ndarray | float) -> np.ndarray:
        """Arc length (m) at spline parameters ``u`` in ``[0, 1]``."""
        u = np.clip(np.asarray(u, dtype=float), 0.0, 1.0)
        k = np.clip(np.searchsorted(self._u, u, side="right") - 1, 0, len(self._u) - 2)
        return self._s[k] + self._integrate(self._u[k], u)

    def param(self, s_m: np.ndarray | float) -> np.ndarray:
        """Spline parameter ``u`` at arc lengths ``s_m`` (clamped to ``[0, length_m]``)."""
        s = np.clip(np.asarray(s_m, dtype=float), 0.0, self.length_m)
        k = np.clip(np.searchsorted(self._s, s, side="right") - 1, 0, len(self._s) - 2)
        lo, hi = self._u[k], self._u[k + 1]
        ds = np.maximum(self._s[k + 1] - self._s[k], 1e-300)
        u = lo + (hi - lo) * (s - self._s[k]) / ds
        for _ in range(4):  # Newton on s(u) = s, kept inside the table interval
            speed = np.maximum(self._speed_u(u), 1e-300)
            u = np.clip(u - (self._s[k] + self._integrate(lo, u) - s) / speed, lo, hi)
        return u

    # ---------------------------------------------------------------- geometry in s

    def point(self, s_m: np.ndarray | float) -> np.ndarray:
        """``p(s)``: ``(dim,)`` for a scalar ``s_m``, ``(n, dim)`` for an array."""
        return self.spline(self.param(s_m))

    def derivatives(self, s_m: np.ndarray | float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``p(s)``, the unit tangent ``dp/ds`` and ``d2p/ds2`` (= curvature ``kappa`` x normal).

        With ``c(u)`` the spline and ``T = c'/|c'|``:
        ``d2p/ds2 = (c'' - (c'' . T) T) / |c'|^2``. A polyline has ``d2p/ds2 = 0``
        (its corners carry no finite curvature). A zero-length path has ``T = 0``.
        """
        u = self.param(s_m)
        c1 = self._d1(u)
        speed = np.linalg.norm(c1, axis=-1, keepdims=True)
        tangent = np.divide(c1, speed, out=np.zeros_like(c1), where=speed > 0)
        if self._d2 is None:
            curv = np.zeros_like(c1)
        else:
            c2 = self._d2(u)
            normal = c2 - np.sum(c2 * tangent, axis=-1, keepdims=True) * tangent
            curv = np.divide(normal, speed**2, out=np.zeros_like(c2), where=speed > 0)
        return self.spline(u), tangent, curv

    def sample(self, spacing_m: float) -> tuple[np.ndarray, np.ndarray]:
        """Arc lengths every ``<= spacing_m`` (ends included) and the points there."""
        n = max(int(np.ceil(self.length_m / spacing_m)), 1) + 1
        s = np.linspace(0.0, self.length_m, n)
        return s, self.point(s)

    @property
    def start(self) -> np.ndarray:
        return self.spline(0.0)

    @property
    def end(self) -> np.ndarray:
        return self.spline(1.0)


# ------------------------------------------------------------------------ smoothing


def _dedupe(pts: np.ndarray) -> np.ndarray:
    keep = np.ones(len(pts), dtype=bool)
    keep[1:] = np.any(np.diff(pts, axis=0) != 0.0, axis=1)
    return pts[keep]


def _chord_param(pts: np.ndarray) -> np.ndarray:
    cum = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])
    return cum / cum[-1] if cum[-1] > 0 else np.linspace(0.0, 1.0, len(pts))


def _resample(pts: np.ndarray, spacing_m: float) -> tuple[np.ndarray, np.ndarray]:
    """Polyline points every ``<= spacing_m`` keeping every vertex, and their chord param."""
    delta = np.diff(pts, axis=0)
    pieces = np.maximum(np.ceil(np.linalg.norm(delta, axis=1) / spacing_m), 1).astype(np.int64)
    ends = np.cumsum(pieces)  # one past each segment's last sample
    seg = np.repeat(np.arange(len(delta)), pieces)
    k = np.arange(len(seg)) - np.repeat(ends - pieces, pieces) + 1  # 1..n each
    t = k * (1.0 / pieces[seg])  # as np.linspace(0, 1, n + 1)[1:]: k * (1 / n), the end 1
    t[ends - 1] = 1.0
    dense = np.concatenate([pts[:1], pts[:-1][seg] + t[:, None] * delta[seg]])
    return dense, _chord_param(dense)


def _world_free(world_or_grid: World | OccupancyGrid, pts: np.ndarray) -> np.ndarray:
    """Boolean ``(n,)``: inside the map and outside every occupied cell."""
    if isinstance(world_or_grid, World):
        return world_or_grid.points_free(pts)
    return ~world_or_grid.is_occupied(pts)


def _fit(dense: np.ndarray, u: np.ndarray, w: np.ndarray, tolerance_m: float) -> BSpline | None:
    """Cubic smoothing spline, ``sum (w_j |c(u_j) - x_j|)^2 <= m tolerance_m^2``, ends pinned.

    Returns ``None`` when FITPACK fails or warns.
    """
    w = w.copy()
    w[[0, -1]] = 1e3  # ends nearly interpolated; then pinned exactly below
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            tck, _ = splprep(dense.T, u=u, w=w, s=len(dense) * tolerance_m**2, k=3)
        except (RuntimeWarning, ValueError, TypeError):
            return None
    t, coeffs, k = tck
    c = np.stack([np.asarray(ci)[: len(t) - k - 1] for ci in coeffs], axis=-1)
    c[0], c[-1] = dense[0], dense[-1]  # clamped knots: c(0) = c[0], c(1) = c[-1]
    return BSpline(t, c, k)


def smooth_path(
    waypoints_m: np.ndarray,
    world_or_grid: World | OccupancyGrid | None = None,
    *,
    planning: OccupancyGrid | None = None,
    tolerance_m: float | None = None,
    window_m: float | None = None,
) -> SplinePath:
    """Smooth an A* polyline by a cubic B-spline that stays clear (paper, Sec. 3.2).

    The polyline is resampled (spacing a quarter of its median segment) and fitted by
    a cubic smoothing spline of RMS deviation ``tolerance_m``. The spline is sampled
    (every half cell of the finer grid, at most) and accepted when each sample at
    chord-length fraction ``u`` passes the tests that the polyline passes at every
    fraction within ``window_m`` of ``u``:

    * *collision-free*: inside the map and outside every occupied cell of
      ``world_or_grid``;
    * *inside the inflated free space*: in a free cell of ``planning``, the A*
      planning grid of :func:`tether.paths.astar.planning_grid`, whose free cells
      keep ``inflate_m`` from obstacles (the paper's ``Rgrid``).

    So the spline stays where the A* polyline is allowed to be, and is exempt only
    where the polyline itself leaves that space (the legs from the robot and to the
    target, which may lie within the inflation). When a sample fails, the fit is
    pulled towards the polyline around the failures (their data weights x4, up to
    four times), then the tolerance is halved (down to 1/16) and, as a last resort,
    the polyline itself is returned (``kind == "polyline"``, C0 only), which passes
    the tests by construction.

    Parameters
    ----------
    waypoints_m
        ``(k, dim)`` polyline, e.g. from :func:`tether.paths.astar.plan_path`.
    world_or_grid
        Obstacles (``World`` or ``OccupancyGrid``); ``None`` skips that test.
    planning
        The inflated planning grid A* used; ``None`` skips that test.
    tolerance_m
        RMS deviation allowed by the fit; the paper gives no smoothing parameter.
        ``None``: half the median segment length (0.375 m for A* steps of
        ``Rgrid = 0.75 m``), enough to round the staircase of grid moves.
    window_m
        How far along the polyline an exemption reaches; ``None``:
        ``2 tolerance_m`` plus one resampling step.

    Returns
    -------
    SplinePath
        Starts at ``waypoints_m[0]`` and ends at ``waypoints_m[-1]`` (to rounding).

    Notes
    -----
    Inside free planning cells a point keeps at least
    ``inflate_m - sqrt(dim) / 2 * cell_m`` from the obstacle cell centres, the same
    bound as the A* polyline's segments. The tests are on samples: between two
    samples (at most half a cell apart) the curve is not looked at. Cost ``O(m)`` for
    the FITPACK fit of ``m`` samples and the look-ups, at most 20 times.
    """
    pts = _dedupe(np.atleast_2d(np.asarray(waypoints_m, dtype=float)))
    if len(pts) < 2:
        return SplinePath.polyline(pts)
    seg = np.linalg.norm(np.diff(pts, axis=0), axis=1)
    step = 0.25 * float(np.median(seg))
    tol = 0.5 * float(np.median(seg)) if tolerance_m is None else float(tolerance_m)
    if tol <= 0:
        return SplinePath.polyline(pts)
    dense, u_data = _resample(pts, step)
    tests = []
    check_m = step
    world_grid = world_or_grid
    if isinstance(world_or_grid, World):
        world_grid = world_or_grid.grid
    for grid in (world_grid, planning):
        if grid is not None:
            check_m = min(check_m, 0.5 * grid.resolution_m)
    if world_or_grid is not None:
        tests.append(lambda x: _world_free(world_or_grid, x))
    if planning is not None:
        tests.append(lambda x: ~planning.is_occupied(x))
    n_check = max(int(np.ceil(seg.sum() / check_m)), 1) + 1
    u_check = np.linspace(0.0, 1.0, n_check)
    # where must the spline pass each test: where the polyline passes it all window long
    poly = np.stack([np.interp(u_check, u_data, dense[:, d]) for d in range(pts.shape[1])], 1)
    win = 2.0 * tol + step if window_m is None else float(window_m)
    half = int(np.ceil(win / (seg.sum() / (n_check - 1))))
    required = [
        ndimage.minimum_filter1d(test(poly).astype(np.uint8), 2 * half + 1, mode="nearest") > 0
        for test in tests
    ]
    weights = np.ones(len(dense))
    reach = max(int(np.ceil(win / step)), 1)
    for factor in _SHRINK:
        for _ in range(_LOCAL_ROUNDS):
            spline = _fit(dense, u_data, weights, tol * factor)
            if spline is None:
                break
            x = spline(u_check)
            bad = np.zeros(n_check, dtype=bool)
            for test, req in zip(tests, required, strict=True):
                bad |= req & ~test(x)
            if not bad.any():
                return SplinePath(spline, kind="spline", tolerance_m=tol * factor)
            # pull the fit towards the polyline around the failures only
            near = np.zeros(len(dense), dtype=bool)
            near[np.searchsorted(u_data, u_check[bad]).clip(0, len(dense) - 1)] = True
            near = ndimage.binary_dilation(near, iterations=reach)
            weights[near] *= 4.0
    return SplinePath.polyline(pts)


# ------------------------------------------------------------ closest point, d_gamma


class ClosestPoint(NamedTuple):
    """The closest path point ``q_gamma`` (paper, Sec. 3.1) to a query ``q``."""

    s_m: float
    point_m: np.ndarray
    distance_m: float


def closest_point(
    path: SplinePath,
    q: Sequence[float] | np.ndarray,
    *,
    previous_s: float | None = None,
    tie_m: float = 1e-6,
) -> ClosestPoint:
    """``q_gamma = argmin_{p in gamma} |p - q|``, the largest arc length among ties (Sec. 3.1).

    The paper: "In case of multiple solutions, we choose the one with the largest
    arc-length, i.e., the one nearest to the target along the path." Every local
    minimum of the distance over the dense table is refined by safeguarded Newton
    steps on ``(c(u) - q) . c'(u) = 0``; among the refined minima (and the path ends),
    those within ``tie_m`` of the least distance count as ties, and the one with the
    largest ``s`` wins.

    Parameters
    ----------
    path
        The path.
    q
        ``(dim,)`` query point (the robot position ``q_i``).
    previous_s
        Not in the paper: when given, only ``s >= previous_s`` is searched (the
        closest point never moves backwards along the path). ``None`` searches the
        whole path, as the paper does.
    tie_m
        Distances within this of the least one are ties.
    """
    q = np.asarray(q, dtype=float).reshape(-1)
    u_tab, pts = path._u, path._pts
    u_min = 0.0 if previous_s is None else float(path.param(previous_s))
    dist = np.linalg.norm(pts - q, axis=1)
    valid = u_tab >= u_min
    dist = np.where(valid, dist, np.inf)
    # local minima of the sampled distance (non-strict, so plateaus give all members)
    left = np.concatenate([[np.inf], dist[:-1]])
    right = np.concatenate([dist[1:], [np.inf]])
    idx = np.flatnonzero(valid & (dist <= left) & (dist <= right))
    lo = u_tab[np.maximum(idx - 1, 0)]
    hi = u_tab[np.minimum(idx + 1, len(u_tab) - 1)]
    lo = np.maximum(lo, u_min)
    u = _refine(path, q, np.clip(u_tab[idx], lo, hi), lo, hi)
    u = np.concatenate([u, [u_min, 1.0]])
    p = path.spline(u)
    d = np.linalg.norm(p - q, axis=1)
    s = path.arc_length(u)
    ties = d <= d.min() + tie_m
    best = int(np.flatnonzero(ties)[np.argmax(s[ties])])
    return ClosestPoint(float(s[best]), p[best], float(d[best]))


def _refine(path: SplinePath, q: np.ndarray, u: np.ndarray, lo: np.ndarray, hi: np.ndarray):
    """Newton on ``g(u) = (c - q) . c'`` in ``[lo, hi]``, keeping the best iterate."""
    if len(u) == 0:
        return u
    best_u = u.copy()
    best_d = np.linalg.norm(path.spline(u) - q, axis=1)
    for _ in range(8):
        c = path.spline(u)
        c1 = path._d1(u)
        c2 = path._d2(u) if path._d2 is not None else np.zeros_like(c1)
        g = np.sum((c - q) * c1, axis=1)
        gp = np.sum(c1 * c1, axis=1) + np.sum((c - q) * c2, axis=1)
        newton = np.where(gp > 0, u - g / np.where(gp > 0, gp, 1.0), np.where(g > 0, lo, hi))
        u = np.clip(newton, lo, hi)
        d = np.linalg.norm(path.spline(u) - q, axis=1)
        better = d < best_d
        best_u[better], best_d[better] = u[better], d[better]
    return best_u


def remaining_length(
    path: SplinePath, q: Sequence[float] | np.ndarray, *, previous_s: float | None = None
) -> float:
    """``d_gamma`` (Sec. 3.1): length (m) of the path from the closest point ``q_gamma`` on."""
    return path.length_m - closest_point(path, q, previous_s=previous_s).s_m


def needs_replan(
    path: SplinePath,
    q: Sequence[float] | np.ndarray,
    r_gamma_m: float,
    *,
    previous_s: float | None = None,
) -> bool:
    """Algorithm 1, line 17: replan when ``|q_i - q_gamma| > R_gamma``."""
    return closest_point(path, q, previous_s=previous_s).distance_m > r_gamma_m
