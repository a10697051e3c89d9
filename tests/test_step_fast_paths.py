"""Fast paths of the multi_target control step: the same bits as their references.

Each compiled or vectorised path of the control step is checked against
the code it replaces (``TETHER_JIT`` off) and, where there is one, a brute-force
oracle: the bookkeeping kernels, the roles' distances to targets, the one-pass
closest-point kernel on paths full of ties, and the election's idle-phase skipping
over lossy, delayed rounds on changing graphs.
"""

from __future__ import annotations

import copy
import math

import numpy as np
import pytest

from tether import floats, jit
from tether.comm import CommParams, MessageLayer
from tether.continuous.connectivity.bookkeep_kernels import min_link_distance_kernel
from tether.continuous.connectivity.pair_kernels import row_norm
from tether.continuous.exploration.election import Election
from tether.continuous.exploration.step_kernels import travel_stretch_kernel
from tether.continuous.exploration.tracking import PathSet, TrackedPath
from tether.paths.bspline import SplinePath


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("seed", range(4))
def test_travel_stretch_kernel_is_the_numpy_bookkeeping(dim: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = 35
    q = rng.normal(0, 30, (n, dim))
    q_new = q + rng.normal(0, 0.3, (n, dim))
    for explorer in (np.zeros(n, bool), np.eye(n, dtype=bool)[3], rng.random(n) < 0.5,
                     np.ones(n, bool)):  # fmt: skip
        ref_t = rng.uniform(0, 5, n)
        fast_t = ref_t.copy()
        far = travel_stretch_kernel(fast_t, q, q_new, explorer)
        ref_t += np.linalg.norm(q_new - q, axis=1)
        np.testing.assert_array_equal(fast_t, ref_t)
        ex = np.flatnonzero(explorer)
        if len(ex) < 2:
            assert far == -1.0
            continue
        d = np.linalg.norm(q_new[ex, None] - q_new[None, ex], axis=-1)
        assert far == float(d.max())
        # oracle: the largest distance over explorer pairs, pair by pair
        oracle = max(math.dist(q_new[i], q_new[j]) for i in ex for j in ex if i < j)
        assert abs(far - oracle) <= 1e-12 * oracle


@pytest.mark.parametrize("dim", [2, 3])
def test_min_link_distance_kernel_is_the_numpy_minimum(dim: int) -> None:
    rng = np.random.default_rng(dim)
    q = rng.normal(0, 10, (40, dim))
    for m in (1, 2, 50, 300):
        pairs = np.sort(rng.choice(40, (m, 2), replace=True), axis=1)
        pairs = pairs[pairs[:, 0] != pairs[:, 1]]
        ref = float(np.linalg.norm(q[pairs[:, 0]] - q[pairs[:, 1]], axis=1).min())
        assert min_link_distance_kernel(q, pairs) == ref
    assert min_link_distance_kernel(q, np.zeros((0, 2), np.int64)) == np.inf


@pytest.mark.parametrize("dim", [2, 3])
def test_row_norms_are_the_norms_of_each_row(dim: int) -> None:
    """``norm(axis=1)`` equals :func:`tether.floats.norm` row by row (and the kernels' row
    norm): the roles' vectorised distances and their robot-by-robot reference rely on it.
    (numpy's own norm of one vector is a BLAS dot, which sums differently on some CPUs.)"""
    rng = np.random.default_rng(10 + dim)
    x = rng.normal(size=(20000, dim)) * rng.uniform(1e-3, 1e3, (20000, 1))
    rows = np.array([floats.norm(r) for r in x])
    np.testing.assert_array_equal(np.linalg.norm(x, axis=1), rows)
    np.testing.assert_array_equal([row_norm(r) for r in x[:2000]], rows[:2000])


def test_distance_to_target_and_target_arrays_follow_the_targets() -> None:
    """The roles' target arrays mirror the target list through a run; distances agree."""
    from tether.config import load_scenario
    from tether.runner import build
    from tether.sim import simulate

    sc = load_scenario("multi_target_office")
    b = build(sc, sc.seed)
    simulate(b.world, b.sensor, b.strategy, b.initial, dt_s=sc.sim.dt_s, max_steps=120,
             rng=b.rng)  # fmt: skip
    pl = b.strategy.planner
    has = np.array([z is not None for z in pl.target])
    assert has.any() and not has.all()  # some robots hold targets, some do not
    np.testing.assert_array_equal(pl._has_target, has)
    for i, z in enumerate(pl.target):
        if z is not None:
            np.testing.assert_array_equal(pl._goal_m[i], z.position_m)
    rng = np.random.default_rng(0)
    for _ in range(20):
        q = rng.normal(0, 20, (len(has), b.world.dim))
        with jit.using(True):
            fast = pl.distance_to_target(q)
        with jit.using(False):
            ref = pl.distance_to_target(q)
        np.testing.assert_array_equal(fast, ref)
        assert np.isinf(fast[~has]).all()
        held = np.flatnonzero(has)
        np.testing.assert_array_equal(pl.targets_of(held),
                                      [pl.target[i].position_m for i in held])  # fmt: skip


def _comb(offset: float) -> TrackedPath:
    """A path running back and forth over the same line, ``offset`` apart (ties)."""
    pts = []
    for k in range(6):
        y = k * offset
        pts += [[0.0, y, 1.0], [8.0, y, 1.0]] if k % 2 == 0 else [[8.0, y, 1.0], [0.0, y, 1.0]]
    return TrackedPath.from_spline(SplinePath.polyline(np.array(pts)))


@pytest.mark.parametrize("offset", [0.0, 3e-7, 2e-6, 0.5])
def test_one_pass_closest_points_on_paths_full_of_ties(offset: float) -> None:
    """Paths over themselves (distances within the tie width): the largest arc length wins,
    as in the numpy reference, while the robots move and the kernel's hints change."""
    rng = np.random.default_rng(int(offset * 1e7) + 1)
    paths = [_comb(offset), _comb(offset * 0.5)]
    ps = PathSet(paths)
    q = np.array([[4.0, 0.0, 1.0], [1.0, 0.0, 1.0]])
    for _ in range(40):
        q = q + rng.normal(0, 0.3, q.shape) * [1, 0.01, 0]
        with jit.using(True):
            fast = ps.states(q, 2.0)
            closest = ps.closest(q)
        with jit.using(False):
            ref = ps.states(q, 2.0)
        for x, y in zip(vars(fast).values(), vars(ref).values(), strict=True):
            np.testing.assert_array_equal(x, y)
        np.testing.assert_array_equal(closest[2], ref.distance_m)
        np.testing.assert_array_equal(closest[3], ref.remaining_m)
        # oracle: among the samples' segments, the distance is the least one
        for r, p in enumerate(paths):
            a, d = p.points[:-1], np.diff(p.points, axis=0)
            t = np.clip(np.einsum("kd,kd->k", q[r] - a, d) / np.einsum("kd,kd->k", d, d), 0, 1)
            least = np.linalg.norm(q[r] - (a + t[:, None] * d), axis=1).min()
            assert abs(ref.distance_m[r] - least) <= 1e-6 + 1e-12


def _drive(seed: int, on: bool) -> list:
    """An election over lossy, delayed rounds on changing graphs; its outcomes and state."""
    rng = np.random.default_rng(seed)
    n = 12
    layer = MessageLayer(n, CommParams(0.2, seed % 3), np.random.default_rng(seed + 100))
    el = Election(n, layer)
    log = []
    with jit.using(on):
        for r in range(600):
            pairs = np.array(
                [(i, i + 1) for i in range(n - 1)]
                + [tuple(sorted(rng.choice(n, 2, replace=False))) for _ in range(4)]
            )
            candidate = rng.random(n) < (0.5 if r % 97 < 60 else 0.0)
            crit = rng.uniform(1, 20, n)
            wants = rng.random(n) < 0.05
            out = el.round(np.unique(pairs, axis=0), candidate, crit, candidate, wants)
            log.append((out.decided, out.became_prime, out.declined, out.opened))
    state = (el.msg, el.token, el.opened_round, el.joined, el.handled, el.candidates)
    return [log, copy.deepcopy(state)]


@pytest.mark.parametrize("seed", range(6))
def test_election_skipping_idle_phases_changes_nothing(seed: int) -> None:
    fast, ref = _drive(seed, True), _drive(seed, False)
    assert fast[0] == ref[0]
    assert sum(len(x[0]) for x in ref[0]) > 3  # elections were decided
    for x, y in zip(fast[1][:5], ref[1][:5], strict=True):
        np.testing.assert_array_equal(x, y)
    assert fast[1][5] == ref[1][5]


@pytest.mark.parametrize("name", ["multi_target_town", "multi_target_office"])
def test_sensing_on_a_grid_in_one_call_is_the_reference(name: str) -> None:
    """Range, line of sight and CSR in one compiled call: the reference's observation."""
    import numba  # noqa: F401  (the compiled pair search runs once numba is loaded)

    from tether.config import load_scenario
    from tether.runner import build
    from tether.sensing import sense
    from tether.sensing.robots import _los_grid, sensed_pairs

    sc = load_scenario(name)
    b = build(sc, sc.seed)
    world, sensor = b.world, b.sensor
    _ = world.grid.distance_field_m  # made: the kernel skips samples by it
    lo, hi = world.bounds_m
    rng = np.random.default_rng(1)
    blocked = 0
    for trial in range(30):
        n = 35
        centre = rng.uniform(lo, hi)
        q = centre + rng.normal(0, [3.0, 8.0, 20.0][trial % 3], (n, world.dim))
        q = np.clip(q, lo, hi)
        with jit.using(True):
            assert _los_grid(world, sensor, n) is world.grid
            fast = sense(q, sensor, np.random.default_rng(trial), world)
        with jit.using(False):
            ref = sense(q, sensor, np.random.default_rng(trial), world)
        for x, y in zip(vars(fast).values(), vars(ref).values(), strict=True):
            assert np.asarray(x).dtype == np.asarray(y).dtype
            np.testing.assert_array_equal(x, y)
        # oracle: the pairs in range minus those the grid's line of sight blocks
        in_range = [(i, j) for i in range(n) for j in range(i + 1, n)
                    if np.sum((q[i] - q[j]) ** 2) <= sensor.range_m**2]  # fmt: skip
        with jit.using(False):
            clear = [p for p in in_range if world.segments_clear(q[p[0]][None], q[p[1]][None])[0]]
            assert [tuple(p) for p in sensed_pairs(q, sensor, world).tolist()] == clear
        assert [tuple(p) for p in fast.pairs.tolist()] == clear
        blocked += len(in_range) - len(clear)
    assert blocked > 0  # some pairs in range were out of sight
