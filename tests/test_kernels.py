"""Compiled kernels (tether.jit) against their reference paths: the same bits.

Every fast path keeps its numpy reference; here both run on the same
inputs and must agree exactly (the arithmetic is the same, in the same order), and the
clearance search also against brute force.
"""

from __future__ import annotations

import numpy as np
import pytest

from _clearance_helpers import box_world, brute
from tether import jit
from tether.continuous.connectivity.gradient import (
    connectivity_force,
    edge_energy,
    lambda2_gradient,
    messages,
)
from tether.continuous.connectivity.params import ConnectivityParams
from tether.continuous.connectivity.weights import compute_weights
from tether.continuous.exploration.tracking import PathSet, TrackedPath
from tether.graph import fiedler, laplacian_dense, pairs_within
from tether.paths.bspline import SplinePath
from tether.world.clearance import ObstacleIndex
from tether.world.grid import OccupancyGrid
from tether.world.los import segment_free
from tether.world.world import World

pytest.importorskip("numba")

PARAMS = ConnectivityParams()
GRAPH_FIELDS = ("pairs", "pair_factor", "dP_di", "dP_dj", "clearance_m", "collision",
                "coll_pairs", "coll_unit", "coll_logd")  # fmt: skip


def both(fn, *args, **kwargs):  # noqa: ANN001, ANN201
    """``fn`` with the kernels on, then off."""
    with jit.using(True):
        fast = fn(*args, **kwargs)
    with jit.using(False):
        ref = fn(*args, **kwargs)
    return fast, ref


def assert_same(a, b) -> None:  # noqa: ANN001
    a, b = np.asarray(a), np.asarray(b)
    assert a.shape == b.shape and a.dtype == b.dtype
    np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("seed", range(3))
def test_clearance_kernel_equals_reference_and_brute_force(dim: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    world = box_world(rng, dim)
    hi = np.array([20.0, 20.0, 8.0])[:dim]
    fast = ObstacleIndex.from_world(world)
    assert fast.grid is not None
    # the same obstacle points without the grid (the kernel then searches every segment)
    plain = ObstacleIndex(fast.points, dim)
    ref = ObstacleIndex.from_world(world)
    q = rng.uniform(0.5, hi - 0.5, (30, dim))
    for step in range(25):
        q = np.clip(q + rng.normal(0.0, [0.02, 0.2, 1.0][step % 3], q.shape), -0.5, hi + 0.5)
        pairs = pairs_within(q, 6.0)
        a, b = q[pairs[:, 0]], q[pairs[:, 1]]
        b[:2] = a[:2]  # zero-length segments
        keys = pairs[:, 0].astype(np.int64) * len(q) + pairs[:, 1]
        want = ref._segment_clearance_reference(a, b, PARAMS.ro_outer_m)
        for got in (fast.segment_clearance_kernel(a, b, PARAMS.ro_outer_m, keys),
                    fast.segment_clearance_kernel(a, b, PARAMS.ro_outer_m),
                    plain.segment_clearance_kernel(a, b, PARAMS.ro_outer_m, keys)):  # fmt: skip
            for x, y in zip(got, want, strict=True):
                assert_same(x, y)
        true = brute(fast.points, a, b)
        near = np.isfinite(want[0])
        np.testing.assert_allclose(want[0][near], true[near], atol=1e-9)
        assert np.all(true[~near] >= PARAMS.ro_outer_m - 1e-9)


def test_clearance_kernel_without_obstacles_and_dispatch() -> None:
    empty = ObstacleIndex(np.zeros((0, 3)), 3)
    d, s, o = empty.segment_clearance_kernel(np.zeros((2, 3)), np.ones((2, 3)), 1.0)
    assert np.all(np.isinf(d)) and o.shape == (2, 3)
    rng = np.random.default_rng(5)
    index = ObstacleIndex(rng.uniform(0, 10, (500, 3)), 3)
    a, b = rng.uniform(0, 10, (40, 3)), rng.uniform(0, 10, (40, 3))
    fast, ref = both(index.segment_clearance, a, b, 1.5)
    for x, y in zip(fast, ref, strict=True):
        assert_same(x, y)


def test_nearest_min_is_the_tree_minimum_where_it_matters() -> None:
    rng = np.random.default_rng(2)
    index = ObstacleIndex.from_world(box_world(rng))
    for low in (np.inf, 3.0, 1.0, 0.2):
        q = rng.uniform(0.5, [19.5, 19.5, 7.5], (20, 3))
        want = min(low, float(index.tree.query(q)[0].min()))
        fast, ref = both(index.nearest_min, q, low)
        assert min(low, fast) == min(low, ref) == want


def _teams(rng: np.random.Generator):  # noqa: ANN202
    """Teams in free space (some packed inside R'c), the box world, and a large one."""
    world = box_world(rng)
    index = ObstacleIndex.from_world(world)
    for n, spread, obstacles in ((6, 4.0, None), (35, 12.0, None), (35, 3.0, None),
                                 (30, 18.0, index), (200, 40.0, None)):  # fmt: skip
        lo = np.array([1.0, 1.0, 1.0])
        q = lo + rng.uniform(0, 1, (n, 3)) * [spread, spread, min(spread, 6.0)]
        yield q, obstacles


@pytest.mark.parametrize("seed", range(3))
def test_weights_gradient_and_force_kernels_equal_reference(seed: int) -> None:
    rng = np.random.default_rng(seed)
    for q, obstacles in _teams(rng):
        fast, ref = both(compute_weights, q, PARAMS, obstacles)
        for name in GRAPH_FIELDS:
            assert_same(getattr(fast, name), getattr(ref, name))
        assert len(ref.coll_pairs) or len(q) < 30  # the collision factors are exercised
        given = both(compute_weights, q, PARAMS, obstacles, pairs=ref.pairs[::2])
        for name in GRAPH_FIELDS:
            assert_same(getattr(given[0], name), getattr(given[1], name))
        lam, nu = ref.fiedler()
        assert_same(*both(edge_energy, ref, nu))
        msg = messages(ref, nu)
        assert_same(*both(lambda2_gradient, ref, msg))
        assert_same(*both(connectivity_force, ref, lam, msg, PARAMS))
        per_robot = lam + rng.normal(0, 0.05, len(q))
        assert_same(*both(connectivity_force, ref, per_robot, msg, PARAMS))


@pytest.mark.parametrize("seed", range(3))
def test_dense_laplacian_kernel_and_fiedler(seed: int) -> None:
    from tether.graph.kernels import laplacian_dense_kernel

    rng = np.random.default_rng(seed)
    for n in (2, 7, 8, 9, 35, 130, 300):
        pairs = np.argwhere(np.triu(rng.random((n, n)) < 0.2, 1))
        w = rng.random(len(pairs)) * np.exp(rng.normal(0, 3, len(pairs)))
        w[rng.random(len(pairs)) < 0.2] = 0.0
        lap = laplacian_dense(n, pairs, w)
        fast = laplacian_dense_kernel(n, pairs.astype(np.int64), w)
        assert_same(fast, lap)
        assert np.array_equal(np.signbit(fast), np.signbit(lap))
        guess = rng.normal(size=n)
        lam, vec = fiedler(n, pairs, w, guess=guess)
        lam2, vec2 = fiedler(n, pairs, w, guess=guess, laplacian=fast)
        assert lam == lam2
        assert_same(vec, vec2)


def test_subset_solver_is_scipys_eigh() -> None:
    import scipy.linalg

    from tether.graph.fiedler import _subset

    rng = np.random.default_rng(1)
    for n in (17, 35, 120):
        pairs = np.argwhere(np.triu(rng.random((n, n)) < 0.3, 1))
        w = rng.random(len(pairs))
        lap = laplacian_dense(n, pairs, w)
        vals, vecs = scipy.linalg.eigh(lap, subset_by_index=[1, 1], driver="evr",
                                       check_finite=False)  # fmt: skip
        lam, vec = _subset(n, pairs, w)
        assert lam == max(float(vals[0]), 0.0)
        assert_same(vec, vecs[:, 0])


def test_fused_substep_force_is_the_chain() -> None:
    """One compiled call per sub-step (substep_kernels.total_force_kernel) = the reference chain."""
    from tether.config import load_scenario
    from tether.continuous.connectivity.dynamics import displacement_step
    from tether.continuous.exploration.motion import travel_args, travel_gains, traveling_forces
    from tether.continuous.exploration.roles import SECONDARY
    from tether.continuous.exploration.substep import fused_total_force
    from tether.runner import build
    from tether.sim import simulate

    sc = load_scenario("multi_target_office")
    sc.team.n_robots = 12
    b = build(sc, sc.seed)
    with jit.using(True):
        res = simulate(b.world, b.sensor, b.strategy, b.initial, dt_s=sc.sim.dt_s, max_steps=40,
                       rng=b.rng)  # fmt: skip
    s, q, v = b.strategy, res.final_state.positions, res.final_state.velocities
    assert (s.planner.role == SECONDARY).any()  # travelers with rho(Theta, Lambda_hat)
    held, cache = s._anchors(), s._current[1]
    with jit.using(False):
        f_lambda = s.connectivity_force(cache)
        ref = f_lambda + traveling_forces(q, v, f_lambda, s.planner, s.consensus.estimate,
                                          s.params, anchors=held)  # fmt: skip
        ref_h = displacement_step(v, ref, s.integ.mass_kg, s.integ.max_step_m)
    with jit.using(True):
        args = travel_args(s.planner, s.consensus.estimate, s.params, held)
        total, f_lam, h = fused_total_force(s, args, travel_gains(s.params))(q, v, cache)
    assert_same(total, ref)
    assert_same(f_lam, f_lambda)
    assert h == ref_h
    # an external force changed after the traveling force (rows replaced): the same too
    rows = np.array([0, 3, 5])

    def adjust(qq, vv, f_lambda, f_ext):  # noqa: ANN001, ANN202
        f_ext = f_ext.copy()
        f_ext[rows] = 0.5 * (qq[rows] - qq[rows][::-1]) - vv[rows]
        return f_ext

    with jit.using(False):
        f_lambda = s.connectivity_force(cache)
        f_ext = traveling_forces(q, v, f_lambda, s.planner, s.consensus.estimate, s.params,
                                 anchors=held)  # fmt: skip
        ref = f_lambda + adjust(q, v, f_lambda, f_ext)
        ref_h = displacement_step(v, ref, s.integ.mass_kg, s.integ.max_step_m)
    with jit.using(True):
        total, _, h = fused_total_force(s, args, travel_gains(s.params), adjust)(q, v, cache)
    assert_same(total, ref)
    assert h == ref_h


def test_path_states_kernel_equals_reference() -> None:
    rng = np.random.default_rng(0)
    paths = []
    for _ in range(8):
        wp = np.cumsum(rng.normal(0, 4, (6, 3)), axis=0)
        paths.append(TrackedPath.from_spline(SplinePath.polyline(wp)))
    # a path that doubles back on itself: closest points tie, the larger arc length wins
    back = np.array([[0.0, 0, 1], [10, 0, 1], [10, 1e-7, 1], [0, 1e-7, 1]])
    paths.append(TrackedPath.from_spline(SplinePath.polyline(back)))
    short = np.array([[0.0, 0, 0], [0, 0, 0.05]])
    paths.append(TrackedPath.from_spline(SplinePath.polyline(short)))
    ps = PathSet(paths)
    for trial in range(60):
        q = np.array([p.points[rng.integers(len(p.s))] for p in paths])
        q += rng.normal(0, [0.0, 0.01, 0.5, 3.0][trial % 4], q.shape)
        v = rng.uniform(1, 3, len(paths)) if trial % 2 else 3.0
        fast, ref = both(ps.states, q, v)
        for x, y in zip(vars(fast).values(), vars(ref).values(), strict=True):
            assert_same(x, y)
        other = 0.0 if trial % 3 else rng.uniform(1, 3, len(paths))  # the same q, reused
        fast, ref = both(ps.states, q, other)
        for x, y in zip(vars(fast).values(), vars(ref).values(), strict=True):
            assert_same(x, y)


@pytest.mark.parametrize("dim", [2, 3])
def test_segment_free_kernel_equals_reference(dim: int) -> None:
    import numba  # noqa: F401  (segment_free uses its kernel only once numba is loaded)

    rng = np.random.default_rng(dim)
    mask = rng.random((30, 25, 12)[:dim]) > 0.05
    shape = np.array(mask.shape)
    for scale in (0.5, 4.0, 20.0):
        a = rng.uniform(-2, shape + 2, (300, dim))
        b = a + rng.normal(0, scale, a.shape)
        b[:5] = a[:5]
        b[5:10, 0] = a[5:10, 0]
        assert_same(*both(segment_free, mask, a, b))


@pytest.mark.parametrize("dim", [2, 3])
def test_segment_free_kernel_skips_by_the_distance_field(dim: int) -> None:
    """With the grid's distance field the kernel reads fewer samples: the same answers."""
    import numba  # noqa: F401
    from scipy import ndimage

    rng = np.random.default_rng(10 + dim)
    world = box_world(rng, dim)
    grid = world.grid
    field = grid.distance_field_m  # now made: segments_clear passes it to the kernel
    free = ~grid.occupied
    np.testing.assert_array_equal(field, ndimage.distance_transform_edt(free) * 0.5)
    lo, hi = grid.origin_m, grid.origin_m + np.array(grid.shape) * 0.5
    for scale in (0.3, 3.0, 12.0):
        a = rng.uniform(lo - 1, hi + 1, (400, dim))
        b = a + rng.normal(0, scale, a.shape)
        b[:5] = a[:5]
        with jit.using(True):
            fast = grid.segments_clear(a, b)
            plain = segment_free(free, (a - lo) * 2.0, (b - lo) * 2.0)
        with jit.using(False):
            ref = grid.segments_clear(a, b)
        assert_same(fast, ref)
        assert_same(plain, ref)
        assert ref.any() and not ref.all()
    empty = OccupancyGrid(np.zeros((10, 10, 4)[:dim], dtype=bool), 0.5, np.zeros(dim))
    assert np.isinf(empty.distance_field_m).all()  # inf everywhere: the whole segment at once
    a = rng.uniform(0.1, 1.9, (50, dim))
    with jit.using(True):
        assert empty.segments_clear(a, a[::-1] + 0.05).all()


def test_switch(monkeypatch: pytest.MonkeyPatch, tmp_path) -> None:  # noqa: ANN001
    with jit.using(False):
        assert not jit.enabled() and not jit.warm()
        with jit.using(True):
            assert jit.enabled()
        assert not jit.enabled()
    # auto: the reference paths until TETHER_JIT_AFTER_S has passed and the cache is ready
    monkeypatch.setattr(jit, "_mode", "auto")
    monkeypatch.setattr(jit, "_switched", False)
    monkeypatch.setattr(jit, "_first_hot", None)
    monkeypatch.setattr(jit, "_next_check", 0.0)
    monkeypatch.setattr(jit, "_spawned", True)  # no background warm-up from a test
    monkeypatch.setenv("TETHER_JIT_AFTER_S", "0")
    monkeypatch.setattr(jit, "marker", lambda: tmp_path / "ready")
    assert not jit.enabled()  # no marker: the cache may be cold
    monkeypatch.setattr(jit, "_next_check", 0.0)
    (tmp_path / "ready").write_text("")
    assert jit.enabled()


@pytest.mark.parametrize(
    ("name", "robots", "steps"),
    [
        ("multi_target_town", 12, 60),
        ("multi_target_office", 0, 60),
        ("connectivity_town", 0, 40),
        ("multi_target_empty", 24, 40),  # 24 robots: the small Fiedler solver, fused sub-step
    ],
)
def test_whole_runs_are_the_same_with_and_without_kernels(name: str, robots: int, steps: int):
    """The kernels change nothing in a run: positions, velocities, lambda2, metrics."""
    from tether.config import load_scenario
    from tether.runner import build
    from tether.sim import simulate

    def run(on: bool):  # noqa: ANN202
        with jit.using(on):
            sc = load_scenario(name)
            if robots:
                sc.team.n_robots = robots
            b = build(sc, sc.seed)
            return simulate(b.world, b.sensor, b.strategy, b.initial, dt_s=sc.sim.dt_s,
                            max_steps=steps, rng=b.rng,
                            collision_distance_m=sc.sim.collision_distance_m)  # fmt: skip

    fast, ref = run(True), run(False)
    assert_same(fast.final_state.positions, ref.final_state.positions)
    assert_same(fast.final_state.velocities, ref.final_state.velocities)
    assert [r.lambda2 for r in fast.records] == [r.lambda2 for r in ref.records]
    assert fast.records == ref.records  # every team metric, bit for bit
    assert fast.strategy_metrics == ref.strategy_metrics


@pytest.mark.parametrize("on", [False, True])
def test_weights_with_an_empty_obstacle_index_are_free_space(on: bool) -> None:
    """An index without points gives the free-space weights (one evaluation)."""
    rng = np.random.default_rng(5)
    q = rng.uniform(0.0, 12.0, (30, 3))
    empty = ObstacleIndex.from_world(World(dim=3))
    assert empty.tree is None
    with jit.using(on):
        a = compute_weights(q, PARAMS, empty)
        b = compute_weights(q, PARAMS, None)
    for name in GRAPH_FIELDS:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
