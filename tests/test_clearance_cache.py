"""Cached line-of-sight clearance bounds: identical to the uncached search and to brute force.

The reference search's cache (numpy) is tested here; the compiled kernel's table in
``tests/test_kernels.py``.
"""

from __future__ import annotations

import numpy as np
import pytest

from tether import jit
from tether.continuous.connectivity.params import ConnectivityParams
from tether.continuous.connectivity.weights import compute_weights
from tether.geometry import point_segment_distance
from tether.world.clearance import ObstacleIndex
from tether.world.grid import OccupancyGrid
from tether.world.world import World

PARAMS = ConnectivityParams()


def box_world(rng: np.random.Generator) -> World:
    """20 x 20 x 8 m at 0.5 m with random boxes."""
    occ = np.zeros((40, 40, 16), dtype=bool)
    for _ in range(6):
        lo = rng.integers(0, 34, size=3)
        size = rng.integers(2, 7, size=3)
        occ[tuple(slice(a, a + s) for a, s in zip(lo, size, strict=True))] = True
    return World(dim=3, grid=OccupancyGrid(occ, 0.5, np.zeros(3)))


def brute_clearance(pts: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.array(
        [
            point_segment_distance(
                pts, np.repeat(a[k : k + 1], len(pts), 0), np.repeat(b[k : k + 1], len(pts), 0)
            ).min()
            for k in range(len(a))
        ]
    )


@pytest.fixture
def reference_path():
    with jit.using(False):
        yield


@pytest.mark.parametrize("seed", range(4))
def test_cached_clearance_equals_uncached_and_brute_force(seed: int, reference_path) -> None:
    rng = np.random.default_rng(seed)
    world = box_world(rng)
    cached = ObstacleIndex.from_world(world)
    assert cached.grid is not None
    q = rng.uniform([1.0, 1.0, 1.0], [19.0, 19.0, 7.0], (30, 3))
    skipped = 0
    for step in range(40):
        # mostly small moves (the cache's regime), sometimes large ones and teleports
        scale = [0.02, 0.2, 1.0][step % 3]
        q = np.clip(q + rng.normal(0.0, scale, q.shape), [0.2] * 3, [19.8, 19.8, 7.8])
        if step % 10 == 9:
            q[rng.integers(len(q))] = rng.uniform([1.0] * 3, [19.0, 19.0, 7.0])
        got = compute_weights(q, PARAMS, cached)
        cold = compute_weights(q, PARAMS, ObstacleIndex.from_world(world))
        np.testing.assert_array_equal(got.pairs, cold.pairs)
        np.testing.assert_array_equal(got.clearance_m, cold.clearance_m)
        np.testing.assert_array_equal(got.pair_factor, cold.pair_factor)
        np.testing.assert_array_equal(got.dP_di, cold.dP_di)
        i, j = got.pairs[:, 0], got.pairs[:, 1]
        plain = ObstacleIndex.from_world(world).segment_clearance(q[i], q[j], PARAMS.ro_outer_m)
        np.testing.assert_array_equal(got.clearance_m, plain[0])  # the search without keys
        brute = brute_clearance(cached.points, q[i], q[j])
        near = np.isfinite(got.clearance_m)
        np.testing.assert_allclose(got.clearance_m[near], brute[near], atol=1e-9)
        assert np.all(brute[~near] >= PARAMS.ro_outer_m - 1e-9)
        # the cache's own bounds are valid lower bounds of the true clearance
        keys = i.astype(np.int64) * len(q) + j
        bound = cached._cached_bound(keys, q[i], q[j])
        assert np.all(bound <= brute + 1e-9)
        skipped += int(np.sum(bound >= PARAMS.ro_outer_m))
    assert skipped > 0  # the cache did settle some segments


@pytest.mark.parametrize("kernel", [False, True])
def test_cache_is_sound_for_a_different_team_with_the_same_keys(kernel: bool) -> None:
    if kernel and not jit.available():
        pytest.skip("numba is not installed")
    with jit.using(kernel):
        _same_keys_other_team()


def _same_keys_other_team() -> None:
    rng = np.random.default_rng(9)
    world = box_world(rng)
    index = ObstacleIndex.from_world(world)
    for _ in range(6):  # unrelated teams of the same size reuse the same pair keys
        q = rng.uniform([1.0] * 3, [19.0, 19.0, 7.0], (25, 3))
        got = compute_weights(q, PARAMS, index)
        cold = compute_weights(q, PARAMS, ObstacleIndex.from_world(world))
        np.testing.assert_array_equal(got.clearance_m, cold.clearance_m)
