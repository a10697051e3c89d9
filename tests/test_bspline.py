"""B-spline paths (continuous-connectivity paper, Sec. 3.1-3.2): smoothing, arc length,
closest point with the largest arc length, remaining length d_gamma.

Oracles: dense sampling of the spline in its own parameter (brute-force distances and
chord-sum arc lengths, independent of the arc-length table), finite differences, the
existing :class:`tether.paths.trajectory.Polyline`, and a k-d tree of the obstacle cells.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial import cKDTree

from tether.paths.astar import plan_path, planning_grid
from tether.paths.bspline import (
    SplinePath,
    closest_point,
    needs_replan,
    remaining_length,
    smooth_path,
)
from tether.paths.bspline import _resample as resample_polyline  # noqa: PLC2701
from tether.paths.trajectory import Polyline
from tether.world.grid import OccupancyGrid

DENSE_U = np.linspace(0.0, 1.0, 200_001)


def random_path(rng: np.random.Generator, dim: int, n: int = 9) -> SplinePath:
    steps = rng.normal(size=(n, dim))
    waypoints = np.cumsum(steps, axis=0) * 2.0
    return smooth_path(waypoints, tolerance_m=0.3)


def chord_lengths(path: SplinePath, u: np.ndarray = DENSE_U) -> np.ndarray:
    """Cumulative chord length of dense samples of the spline (arc-length oracle)."""
    pts = path.spline(u)
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(pts, axis=0), axis=1))])


# ------------------------------------------------------------------- arc length


@pytest.mark.parametrize("dim", [2, 3])
def test_arc_length_matches_dense_chords(dim):
    rng = np.random.default_rng(dim)
    for _ in range(5):
        path = random_path(rng, dim)
        assert path.kind == "spline"
        cum = chord_lengths(path)
        assert path.length_m == pytest.approx(cum[-1], rel=1e-8)
        u = rng.uniform(0, 1, 50)
        np.testing.assert_allclose(path.arc_length(u), np.interp(u, DENSE_U, cum), atol=1e-6)
        s = rng.uniform(0, path.length_m, 50)
        np.testing.assert_allclose(path.arc_length(path.param(s)), s, atol=1e-9)
        np.testing.assert_allclose(path.point(s), path.spline(path.param(s)))


def test_polyline_path_matches_the_polyline():
    pts = np.array([[0.0, 0.0, 0.0], [3.0, 0.0, 0.0], [3.0, 4.0, 0.0], [3.0, 4.0, 2.0]])
    path = SplinePath.polyline(pts)
    ref = Polyline(pts)
    assert path.length_m == pytest.approx(ref.length_m, rel=1e-12)
    for s in np.linspace(0, ref.length_m, 37):
        np.testing.assert_allclose(path.point(s), ref.at(s), atol=1e-9)
    _, tangent, curv = path.derivatives(1.0)
    np.testing.assert_allclose(tangent, [1.0, 0.0, 0.0], atol=1e-12)
    np.testing.assert_array_equal(curv, 0.0)


@pytest.mark.parametrize("dim", [2, 3])
def test_derivatives_match_finite_differences(dim):
    rng = np.random.default_rng(10 + dim)
    h = 1e-4
    for _ in range(4):
        path = random_path(rng, dim)
        s = rng.uniform(2 * h, path.length_m - 2 * h, 40)
        _, tangent, curv = path.derivatives(s)
        np.testing.assert_allclose(np.linalg.norm(tangent, axis=1), 1.0, atol=1e-12)
        fd_t = (path.point(s + h) - path.point(s - h)) / (2 * h)
        np.testing.assert_allclose(tangent, fd_t, atol=1e-6)
        fd_k = (path.derivatives(s + h)[1] - path.derivatives(s - h)[1]) / (2 * h)
        np.testing.assert_allclose(curv, fd_k, atol=1e-4 * (1 + np.abs(curv).max()))
        np.testing.assert_allclose(np.sum(curv * tangent, axis=1), 0.0, atol=1e-9)


def test_circle_curvature_is_one_over_radius():
    radius = 5.0
    th = np.linspace(0.0, np.pi, 60)
    path = smooth_path(radius * np.c_[np.cos(th), np.sin(th)], tolerance_m=0.002)
    assert path.length_m == pytest.approx(np.pi * radius, rel=1e-3)
    s = np.linspace(1.0, path.length_m - 1.0, 20)
    p, _, curv = path.derivatives(s)
    np.testing.assert_allclose(np.linalg.norm(curv, axis=1), 1.0 / radius, rtol=0.05)
    np.testing.assert_allclose(curv / np.linalg.norm(curv, axis=1)[:, None], -p / radius, atol=0.05)


# ----------------------------------------------------------------- closest point


@pytest.mark.parametrize("dim", [2, 3])
def test_closest_point_vs_brute_force(dim):
    rng = np.random.default_rng(20 + dim)
    for _ in range(4):
        path = random_path(rng, dim)
        dense = path.spline(DENSE_U)
        cum = chord_lengths(path)
        lo, hi = dense.min(axis=0) - 2, dense.max(axis=0) + 2
        for q in rng.uniform(lo, hi, size=(25, dim)):
            cp = closest_point(path, q)
            d_bf = np.linalg.norm(dense - q, axis=1)
            k = int(np.argmin(d_bf))
            assert cp.distance_m <= d_bf[k] + 1e-6  # as close as any sample, up to tie_m
            assert cp.distance_m >= d_bf[k] - 1e-3  # and samples are ~1e-4 m apart
            np.testing.assert_allclose(cp.point_m, path.point(cp.s_m), atol=1e-8)
            assert cp.distance_m == pytest.approx(np.linalg.norm(cp.point_m - q), abs=1e-12)
            # no sample as close as the answer lies farther along the path
            near = d_bf <= cp.distance_m + 1e-9
            if near.any():
                assert cp.s_m >= cum[near].max() - 1e-3


def test_ties_go_to_the_largest_arc_length():
    # a V: the two arms are equally close to (0, 1)
    v_path = SplinePath.polyline([[-1.0, 1.0], [0.0, 0.0], [1.0, 1.0]])
    cp = closest_point(v_path, [0.0, 1.0])
    np.testing.assert_allclose(cp.point_m, [0.5, 0.5], atol=1e-9)
    assert cp.s_m == pytest.approx(1.5 * math.sqrt(2.0), abs=1e-9)
    # the two ends of a smooth U are equally close to (0, 2): the end wins
    u_path = smooth_path([[-1.0, 1.0], [-1.0, 0.0], [1.0, 0.0], [1.0, 1.0]], tolerance_m=0.2)
    assert u_path.kind == "spline"
    cp = closest_point(u_path, [0.0, 2.0])
    assert cp.s_m == pytest.approx(u_path.length_m, abs=1e-9)
    np.testing.assert_allclose(cp.point_m, [1.0, 1.0], atol=1e-12)
    # a clear winner is kept even if it comes first
    cp = closest_point(v_path, [-0.001, 1.0])
    np.testing.assert_allclose(cp.point_m, [-0.5005, 0.5005], atol=1e-9)  # on the first arm
    # a plateau (all points of a half circle at the same distance): the last one
    th = np.linspace(0.0, np.pi, 181)
    arc = SplinePath.polyline(np.c_[np.cos(th), np.sin(th)])
    cp = closest_point(arc, [0.0, 0.0], tie_m=1e-3)
    assert cp.s_m == pytest.approx(arc.length_m)


def test_previous_s_searches_ahead_only():
    rng = np.random.default_rng(31)
    path = random_path(rng, 2, n=12)
    dense = path.spline(DENSE_U)
    cum = chord_lengths(path)
    for q in rng.uniform(dense.min(axis=0), dense.max(axis=0), size=(20, 2)):
        prev = float(rng.uniform(0, path.length_m))
        cp = closest_point(path, q, previous_s=prev)
        assert cp.s_m >= prev - 1e-9
        ahead = cum >= prev
        assert cp.distance_m <= np.linalg.norm(dense[ahead] - q, axis=1).min() + 1e-12
        assert cp.distance_m >= closest_point(path, q).distance_m - 1e-12


def test_remaining_length_and_replanning():
    rng = np.random.default_rng(41)
    for dim in (2, 3):
        path = random_path(rng, dim)
        cum = chord_lengths(path)
        for u0 in rng.uniform(0, 1, 10):
            q = path.spline(u0)
            k = int(np.searchsorted(DENSE_U, u0))
            expected = cum[-1] - cum[k]  # the chords from (about) u0 to the end
            cp = closest_point(path, q)
            if cp.distance_m > 1e-9:
                continue  # the path comes back through q later: d_gamma is shorter
            assert remaining_length(path, q) == pytest.approx(expected, abs=2e-4)
        q = path.point(0.3 * path.length_m)
        normal = np.zeros(dim)
        normal[0] = 1.0
        far = q + 10.0 * normal
        d = closest_point(path, far).distance_m
        assert needs_replan(path, far, d - 1e-6) and not needs_replan(path, far, d + 1e-6)


# -------------------------------------------------------------------- smoothing


def test_smoothing_pins_the_ends_and_rounds_corners():
    rng = np.random.default_rng(51)
    for dim in (2, 3):
        steps = rng.integers(-1, 2, size=(30, dim)) * 0.75  # an A*-like staircase
        steps[np.all(steps == 0, axis=1), 0] = 0.75
        pts = np.concatenate([np.zeros((1, dim)), np.cumsum(steps, axis=0)]) + 0.3
        path = smooth_path(pts)
        median = np.median(np.linalg.norm(np.diff(pts, axis=0), axis=1))
        assert path.kind == "spline" and path.tolerance_m == pytest.approx(0.5 * median)
        np.testing.assert_allclose(path.start, pts[0], rtol=0, atol=1e-12)
        np.testing.assert_allclose(path.end, pts[-1], rtol=0, atol=1e-12)
        poly = Polyline(pts)
        assert path.length_m < poly.length_m  # corners cut
        # close to the polyline: within a few tolerances everywhere
        dense = path.spline(np.linspace(0, 1, 4001))
        seg_t = np.linspace(0, 1, 50)[:, None, None]
        ref = (pts[:-1] + seg_t * (pts[1:] - pts[:-1])).reshape(-1, dim)
        assert cKDTree(ref).query(dense)[0].max() < 3 * path.tolerance_m


def test_degenerate_inputs():
    one = smooth_path(np.array([[1.0, 2.0, 3.0]]))
    assert one.length_m == 0.0
    np.testing.assert_array_equal(one.point(0.5), [1.0, 2.0, 3.0])
    assert closest_point(one, [0.0, 0.0, 0.0]).s_m == 0.0
    line = smooth_path(np.array([[0.0, 0.0], [3.0, 4.0]]))
    assert line.length_m == pytest.approx(5.0, rel=1e-9)
    _, tangent, curv = line.derivatives(np.linspace(0, 5, 11))
    np.testing.assert_allclose(tangent, np.tile([0.6, 0.8], (11, 1)), atol=1e-9)
    np.testing.assert_allclose(curv, 0.0, atol=1e-9)


def box_grid(rng, shape, res_m, n_boxes) -> OccupancyGrid:
    occ = np.zeros(shape, dtype=bool)
    for _ in range(n_boxes):
        lo = rng.integers(0, np.asarray(shape) - 2)
        size = rng.integers(3, np.maximum(np.asarray(shape) // 3, 4))
        occ[tuple(slice(a, a + s) for a, s in zip(lo, size, strict=True))] = True
    return OccupancyGrid(occ, res_m, np.zeros(len(shape)))


def in_occupied_cell(grid: OccupancyGrid, pts: np.ndarray) -> np.ndarray:
    cells = np.floor((pts - grid.origin_m) / grid.resolution_m).astype(int)
    inside = np.all((cells >= 0) & (cells < grid.shape), axis=1)
    hit = ~inside
    hit[inside] = grid.occupied[tuple(cells[inside].T)]
    return hit


def planned_paths(dim: int, seed: int, n_maps: int = 4):
    """(grid, planning grid, A* polylines) on random box maps, ends well clear."""
    rng = np.random.default_rng(seed)
    res, cell = 0.25, 0.75
    shape = (80, 80) if dim == 2 else (48, 48, 12)
    clear = cell + math.sqrt(dim) * (cell / 2 + res)  # ends inside free planning cells
    for _ in range(n_maps):
        grid = box_grid(rng, shape, res, 14 if dim == 2 else 18)
        plan = planning_grid(grid, cell_m=cell)
        ok = np.argwhere(grid.distance_field_m >= clear)
        ends = grid.to_world(ok[rng.choice(len(ok), size=12, replace=False)])
        paths = [
            plan_path(grid, a, b, cell_m=cell, planning=plan) for a, b in ends.reshape(6, 2, dim)
        ]
        yield grid, plan, [p for p in paths if p is not None and len(p) > 4]


@pytest.mark.parametrize("dim", [2, 3])
def test_smoothed_paths_stay_in_the_free_space(dim):
    res, cell = 0.25, 0.75
    bound = cell - math.sqrt(dim) / 2 * cell - res / 4  # free planning cells, sample slack
    n_paths = n_unchecked_violations = 0
    for grid, plan, paths in planned_paths(dim, 60 + dim):
        tree = cKDTree(grid.obstacle_points())
        for wp in paths:
            for tol in (None, 1.0, 2.0):
                path = smooth_path(wp, grid, planning=plan, tolerance_m=tol)
                np.testing.assert_allclose(path.start, wp[0], rtol=0, atol=1e-12)
                np.testing.assert_allclose(path.end, wp[-1], rtol=0, atol=1e-12)
                _, dense = path.sample(res / 20)
                assert not in_occupied_cell(grid, dense).any(), "the smoothed path hits"
                assert tree.query(dense)[0].min() >= bound - 1e-9
                n_paths += 1
                # the same fit without the checks does cut into the inflation somewhere
                raw = smooth_path(wp, tolerance_m=2.0)
                n_unchecked_violations += tree.query(raw.sample(res / 20)[1])[0].min() < bound
    assert n_paths >= 30
    assert n_unchecked_violations > 0  # the maps are hard enough for the check to matter


def test_polyline_fallback(monkeypatch):
    import tether.paths.bspline as bspline

    wp = np.array([[0.5, 0.5], [1.5, 1.5], [2.5, 2.5], [3.5, 1.5], [4.5, 0.5]])
    plan = OccupancyGrid(np.zeros((5, 3), dtype=bool), 1.0)
    assert smooth_path(wp, plan).kind == "spline"
    ref = Polyline(wp)
    s = np.linspace(0, ref.length_m, 9)
    # every fit leaves the map (FITPACK result shifted by 5 m): the polyline comes back
    fit = bspline._fit

    def shifted(*args):
        spline = fit(*args)
        return None if spline is None else bspline.BSpline(spline.t, spline.c + 5.0, spline.k)

    monkeypatch.setattr(bspline, "_fit", shifted)
    path = smooth_path(wp, plan)
    assert path.kind == "polyline"
    np.testing.assert_allclose(path.point(s), [ref.at(x) for x in s], atol=1e-9)
    # without obstacles to check, the shifted fit is (wrongly) accepted: the check is
    # what rejects it
    assert smooth_path(wp).kind == "spline"
    # FITPACK failing everywhere: the polyline too
    monkeypatch.setattr(bspline, "_fit", lambda *args: None)
    assert smooth_path(wp, plan).kind == "polyline"


@pytest.mark.parametrize("seed", range(20))
def test_the_fit_data_are_each_segment_cut_evenly_every_vertex_kept(seed: int) -> None:
    """The samples a spline is fitted to: segment by segment, ``np.linspace`` cut into the
    fewest pieces no longer than the spacing (the oracle), bit for bit, with the chord
    parameter from 0 to 1."""
    rng = np.random.default_rng(seed)
    pts = np.cumsum(rng.normal(size=(rng.integers(2, 30), rng.integers(2, 4))), axis=0)
    pts = np.round(pts * 4) / 4 if seed % 2 else pts * 10.0 ** rng.integers(-1, 2)
    pts = pts[np.r_[True, np.any(np.diff(pts, axis=0) != 0, axis=1)]]  # as smooth_path gives
    spacing = float(rng.uniform(0.05, 2.0))
    oracle = [pts[:1]]
    for a, b in zip(pts[:-1], pts[1:], strict=True):
        n = max(math.ceil(np.linalg.norm(b - a) / spacing), 1)
        oracle.append(a + np.linspace(0.0, 1.0, n + 1)[1:, None] * (b - a))
    dense, u = resample_polyline(pts, spacing)
    assert np.array_equal(dense, np.concatenate(oracle))
    assert u[0] == 0.0 and u[-1] == 1.0 and np.all(np.diff(u) > 0)
