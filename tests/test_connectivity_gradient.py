"""Weights, potential and the analytic lambda2 gradient against independent oracles."""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest

from tether.continuous.connectivity.gradient import Messages, lambda2_gradient, messages
from tether.continuous.connectivity.params import ConnectivityParams
from tether.continuous.connectivity.potential import (
    potential,
    potential_slope,
    smooth_step,
    smooth_step_log_derivative,
)
from tether.continuous.connectivity.weights import compute_weights
from tether.geometry import point_segment_distance
from tether.world.clearance import ObstacleIndex
from tether.world.grid import OccupancyGrid
from tether.world.world import World

PARAMS = ConnectivityParams()  # Table 2, empty space and town


def box_world(dim: int, rng: np.random.Generator, boxes: int = 4) -> World:
    """A 20 m (x 8 m) grid at 0.5 m with random boxes."""
    shape = (40, 40) if dim == 2 else (40, 40, 16)
    occ = np.zeros(shape, dtype=bool)
    for _ in range(boxes):
        lo = rng.integers(0, 34, size=dim)
        size = rng.integers(2, 7, size=dim)
        occ[tuple(slice(a, a + s) for a, s in zip(lo, size, strict=True))] = True
    return World(dim=dim, grid=OccupancyGrid(occ, 0.5, np.zeros(dim)))


def random_config(world: World, n: int, rng: np.random.Generator, obs: ObstacleIndex):
    """Random positions in free space whose weighted graph is connected, with a simple lambda2."""
    lo, hi = world.bounds_m
    centre = (lo + hi) / 2
    spread = 2.2 * n ** (1 / world.dim)
    for _ in range(1000):
        q = centre + rng.uniform(-spread, spread, size=(n, world.dim))
        if obs.tree is not None and obs.tree.query(q)[0].min() < 0.3:
            continue
        g = compute_weights(q, PARAMS, obs)
        vals = np.linalg.eigvalsh(g.laplacian_dense())
        if vals[1] > 1e-3 and vals[2] - vals[1] > 1e-3 * max(vals[2], 1.0):
            return q
    raise RuntimeError("no configuration found")


def lambda2_at(q: np.ndarray, obs: ObstacleIndex) -> float:
    return compute_weights(q, PARAMS, obs).fiedler()[0]


def finite_difference(q: np.ndarray, obs: ObstacleIndex, h: float = 1e-6) -> np.ndarray:
    fd = np.zeros_like(q)
    for idx in np.ndindex(*q.shape):
        qp, qm = q.copy(), q.copy()
        qp[idx] += h
        qm[idx] -= h
        fd[idx] = (lambda2_at(qp, obs) - lambda2_at(qm, obs)) / (2 * h)
    return fd


# --------------------------------------------------------------------------- smooth step


def test_smooth_step_values_derivative_and_symmetry() -> None:
    lo, hi = 1.0, 2.5
    x = np.linspace(0.0, 3.5, 2001)
    s, ds = smooth_step(x, lo, hi)
    assert np.all(s[x <= lo] == 0.0) and np.all(s[x >= hi] == 1.0)
    t = (x - lo) / (hi - lo)
    core = (t > 0.01) & (t < 0.99)  # outside it, S or 1 - S underflows the double range
    assert np.all(s[core] > 0) and np.all(smooth_step(lo + hi - x, lo, hi)[0][core] > 0)
    assert np.all(np.diff(s) >= 0)
    np.testing.assert_allclose(smooth_step(lo + hi - x, lo, hi)[0], 1 - s, atol=1e-12)
    h = 1e-6
    fd = (smooth_step(x + h, lo, hi)[0] - smooth_step(x - h, lo, hi)[0]) / (2 * h)
    np.testing.assert_allclose(ds, fd, atol=1e-6)
    inside = (x > lo + 0.05) & (x < hi - 0.05)
    np.testing.assert_allclose(smooth_step_log_derivative(x, lo, hi)[inside],
                               ds[inside] / s[inside], rtol=1e-9)  # fmt: skip
    # flat at both ends: derivative tends to 0
    assert smooth_step(lo + 1e-3, lo, hi)[1] < 1e-100
    assert smooth_step(hi - 1e-3, lo, hi)[1] < 1e-100


def test_potential_shape() -> None:
    p = ConnectivityParams(lambda2_min=0.1, lambda2_null=1.0, potential_gain=2.0)
    assert potential(1.0, p) == (0.0, 0.0) and potential(3.0, p) == (0.0, 0.0)
    assert potential(0.1, p)[0] == np.inf
    lam = np.linspace(0.11, 0.999, 200)
    v = np.array([potential(x, p)[0] for x in lam])
    dv = np.array([potential(x, p)[1] for x in lam])
    assert np.all(np.diff(v) < 0) and np.all(v > 0)
    h = 1e-7
    fd = np.array([(potential(x + h, p)[0] - potential(x - h, p)[0]) / (2 * h) for x in lam])
    np.testing.assert_allclose(dv, fd, rtol=1e-5)
    np.testing.assert_allclose(potential_slope(lam, p), dv, rtol=1e-12)
    assert abs(potential(1.0 - 1e-6, p)[1]) < 1e-4  # C1 at lambda2_null
    assert potential(0.1 + 1e-9, p)[0] > 1e8  # unbounded at lambda2_min


# --------------------------------------------------------------------------- weights


@pytest.mark.parametrize("dim", [2, 3])
def test_segment_clearance_matches_brute_force(dim: int) -> None:
    rng = np.random.default_rng(dim)
    world = box_world(dim, rng, boxes=10)
    obs = ObstacleIndex.from_world(world)
    assert obs.grid is not None  # the pre-screen is in use
    everything = obs.points  # the surface of the occupied cells (see the next test)
    a = rng.uniform(world.bounds_m[0], world.bounds_m[1], size=(400, dim))
    b = a + rng.normal(scale=3.0, size=(400, dim))
    within = 1.75
    dist, param, closest = obs.segment_clearance(a, b, within)
    brute = np.array([point_segment_distance(everything, np.repeat(a[k:k + 1], len(everything), 0),
                                             np.repeat(b[k:k + 1], len(everything), 0)).min()
                      for k in range(len(a))])  # fmt: skip
    near = np.isfinite(dist)
    np.testing.assert_allclose(dist[near], brute[near], atol=1e-9)
    assert np.all(brute[~near] >= within - 1e-9)
    assert near.sum() > 40 and (~near).sum() > 40
    p_star = a[near] + param[near, None] * (b[near] - a[near])
    np.testing.assert_allclose(np.linalg.norm(p_star - closest[near], axis=1), dist[near])


@pytest.mark.parametrize("with_grid", [False, True])
def test_segment_clearance_just_below_the_threshold(with_grid: bool) -> None:
    """Segments at 0.99 within_m from one obstacle point, its foot anywhere between samples.

    The nearest candidate sample is then farther than ``within_m`` from the point;
    the search must still find it (a regression: it once queried samples only up to
    ``within_m``).
    """
    within = 1.75
    grid = None
    point = np.zeros((1, 3))
    if with_grid:
        occ = np.zeros((40, 40, 40), dtype=bool)
        occ[20, 20, 20] = True
        grid = OccupancyGrid(occ, 0.25, np.full(3, -5.0))
        point = grid.to_world(np.array([[20, 20, 20]]))
    obs = ObstacleIndex(point, 3, grid)
    a, b = [], []
    for length in np.linspace(1.0, 6.0, 26):
        for t in np.linspace(0.0, 1.0, 21):
            start = point[0] + np.array([-t * length, 0.99 * within, 0.0])
            a.append(start)
            b.append(start + np.array([length, 0.0, 0.0]))
    dist, param, closest = obs.segment_clearance(np.array(a), np.array(b), within)
    np.testing.assert_allclose(dist, 0.99 * within, rtol=1e-12)
    np.testing.assert_allclose(closest, np.repeat(point, len(a), 0))


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("centred", [True, False])
def test_grid_lower_bound_is_a_true_lower_bound(dim: int, centred: bool) -> None:
    """The distance-field pre-screen never exceeds the exact segment clearance.

    With obstacle points at cell centres the margin is one half cell diagonal
    (query sample to its cell centre), otherwise two (plus the obstacle point
    to its centre); points jittered inside their cells exercise the second case.
    """
    rng = np.random.default_rng(10 + dim)
    world = box_world(dim, rng, boxes=10)
    obs = ObstacleIndex.from_world(world)
    pts = obs.points
    if not centred:
        half = 0.5 * world.grid.resolution_m * (1 - 1e-9)
        pts = pts + rng.uniform(-half, half, size=pts.shape)
        obs = ObstacleIndex(pts, dim, world.grid)
    assert obs._centred is centred
    a = rng.uniform(world.bounds_m[0], world.bounds_m[1], size=(1500, dim))
    b = a + rng.normal(scale=2.0, size=(1500, dim))
    lower = obs._lower_bound(a, b)
    exact = np.array([point_segment_distance(pts, np.repeat(a[k:k + 1], len(pts), 0),
                                             np.repeat(b[k:k + 1], len(pts), 0)).min()
                      for k in range(len(a))])  # fmt: skip
    slack = exact - lower
    assert slack.min() >= -1e-12
    # the test has teeth: dropping one half diagonal and the sample-spacing term (at
    # most half a cell) from the margin would give a violation somewhere
    assert slack.min() < obs._half_diag_m + 0.5 * world.grid.resolution_m
    assert (lower >= 1.75).mean() > 0.2  # and the pre-screen does skip many segments
    two_level = obs._lower_bound(a, b, 1.75)  # coarse pass, fine pass where needed
    assert np.all(two_level <= exact + 1e-12)
    assert (two_level >= 1.75).mean() > 0.2


def test_surface_points_give_the_same_clearance() -> None:
    rng = np.random.default_rng(5)
    world = box_world(3, rng, boxes=5)
    surf = world.grid.surface_points(outside_is_free=True)
    assert len(surf) < len(world.obstacle_points)
    free = rng.uniform(0, 20, size=(500, 3))
    free[:, 2] = rng.uniform(0, 8, size=500)
    free = free[~world.grid.is_occupied(free)]
    full = ObstacleIndex(world.obstacle_points, 3).tree.query(free)[0]
    thin = ObstacleIndex(surf, 3).tree.query(free)[0]
    np.testing.assert_allclose(thin, full)


@pytest.mark.parametrize("seed", range(10))
def test_weights_vanish_exactly_under_conditions_a_b_c(seed: int) -> None:
    rng = np.random.default_rng(seed)
    world = box_world(3, rng, boxes=5)
    obs = ObstacleIndex.from_world(world)
    q = rng.uniform(0, 20, size=(12, 3))
    q[:, 2] = rng.uniform(0, 8, size=12)
    g = compute_weights(q, PARAMS, obs, pairs=np.array(np.triu_indices(12, 1)).T)
    i, j = g.pairs.T
    d = np.linalg.norm(q[i] - q[j], axis=1)
    pts = world.obstacle_points
    clear = np.array([point_segment_distance(pts, np.repeat(q[a:a + 1], len(pts), 0),
                                             np.repeat(q[b:b + 1], len(pts), 0)).min()
                      for a, b in g.pairs])  # fmt: skip
    dist_all = np.linalg.norm(q[:, None] - q[None], axis=-1) + np.eye(12) * 1e9
    crowded = dist_all.min(axis=1) <= PARAMS.rc_m
    expect_zero = (d >= PARAMS.rs_m) | (clear <= PARAMS.ro_m) | crowded[i] | crowded[j]
    w = g.weights
    assert np.all(w[expect_zero] == 0.0)
    assert np.all(w[~expect_zero] > 0.0)
    assert np.all(w <= 1.0)


# --------------------------------------------------------------------------- gradient


@pytest.mark.parametrize("dim", [2, 3])
def test_gradient_matches_finite_differences(dim: int) -> None:
    """eq. (18) plus collision terms vs central differences of the exact lambda2."""
    active_obstacle = active_collision = 0
    for seed in range(12):
        rng = np.random.default_rng(100 * dim + seed)
        world = box_world(dim, rng, boxes=8)
        obs = ObstacleIndex.from_world(world)
        q = random_config(world, int(rng.integers(5, 9)), rng, obs)
        g = compute_weights(q, PARAMS, obs)
        lam, nu = g.fiedler()
        grad = lambda2_gradient(g, messages(g, nu))
        fd = finite_difference(q, obs)
        scale = max(np.abs(fd).max(), 1e-3)
        assert np.abs(grad - fd).max() < 1e-5 * scale + 1e-8, seed
        band = np.isfinite(g.clearance_m) & (g.clearance_m > PARAMS.ro_m) & (g.weights > 0)
        active_obstacle += int(band.sum())
        active_collision += int((g.coll_logd > 0).sum())
    assert active_obstacle > 0 and active_collision > 0  # both extra terms were exercised


def test_collision_cross_terms_are_needed() -> None:
    """Eq. (18) restricted to dW_ij/dq_i misses the collision factor's cross terms."""
    worst = 0.0
    for seed in range(10):
        rng = np.random.default_rng(seed)
        world = World(dim=2, bounds_m=np.array([[0.0, 0.0], [20.0, 20.0]]))
        obs = ObstacleIndex.from_world(world)
        q = random_config(world, 6, rng, obs)
        g = compute_weights(q, PARAMS, obs)
        if not (g.coll_logd > 0).any():
            continue
        lam, nu = g.fiedler()
        msg = messages(g, nu)
        pair_only = lambda2_gradient(g, Messages(msg.nu, msg.collision, 0 * msg.edge_energy))
        worst = max(worst, np.abs(pair_only - finite_difference(q, obs)).max())
    assert worst > 1e-3


@pytest.mark.parametrize("seed", range(18))
def test_lambda2_matches_networkx(seed: int) -> None:
    """Small teams use the full ``eigh``, larger ones (> 16) the second eigenpair only."""
    rng = np.random.default_rng(seed)
    world = box_world(3, rng, boxes=6)
    obs = ObstacleIndex.from_world(world)
    n = int(rng.integers(5, 15)) if seed < 12 else int(rng.integers(17, 60))
    q = random_config(world, n, rng, obs)
    g = compute_weights(q, PARAMS, obs)
    lam, nu = g.fiedler()
    graph = nx.Graph()
    graph.add_nodes_from(range(len(q)))
    for (a, b), w in zip(*g.active(), strict=True):
        graph.add_edge(int(a), int(b), weight=float(w))
    ref = nx.algebraic_connectivity(graph, weight="weight", tol=1e-12, method="lanczos")
    assert lam == pytest.approx(ref, rel=1e-7, abs=1e-10)
    np.testing.assert_allclose(g.laplacian_dense() @ nu, lam * nu, atol=1e-9)
