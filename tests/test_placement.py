"""Team placement ``random_connected``: the old process's properties and statistics, O(n log n).

The reference is the one-robot-at-a-time placement it replaces
(``_placement_reference.py``): every placement must keep its properties (a
connected disc graph of radius ``spacing_m``, robots ``min_separation_m`` apart,
in free space) and its statistics (spread, nearest-neighbour distance, degree),
and large teams must be placed, or refused, quickly.
"""

from __future__ import annotations

import time

import numpy as np
import pytest
from PIL import Image
from scipy.spatial import cKDTree

from _placement_reference import random_connected as reference
from tether.graph import is_connected, pairs_within
from tether.team import _first_come, random_connected
from tether.world.maps import load_map
from tether.world.world import World


def _walls(tmp_path) -> World:
    img = np.full((60, 80), 255, dtype=np.uint8)  # 80 m x 60 m at 1 m per cell
    img[[0, -1], :] = img[:, [0, -1]] = 0
    img[10:50, 40] = 0  # a wall with gaps above and below
    img[30, 10:35] = 0
    Image.fromarray(img).save(tmp_path / "walls.png")
    grid = load_map(tmp_path / "walls.png", resolution_m=1.0)
    return World(dim=2, grid=grid, obstacle_points=grid.surface_points())


def _check(pos: np.ndarray, world: World, n: int, spacing: float, min_sep: float) -> None:
    assert pos.shape == (n, world.dim) and np.isfinite(pos).all()
    assert world.points_free(pos).all()
    if n > 1:
        nearest, _ = cKDTree(pos).query(pos, k=2)
        assert nearest[:, 1].min() >= min_sep
    pairs = pairs_within(pos, spacing)
    if world.has_obstacles:  # links through walls do not count
        pairs = pairs[world.segments_clear(pos[pairs[:, 0]], pos[pairs[:, 1]])]
    assert is_connected(n, pairs)


@pytest.mark.parametrize("seed", range(4))
@pytest.mark.parametrize(
    ("dim", "n", "spacing", "min_sep"),
    [(2, 12, 8.0, 2.0), (2, 500, 8.0, 2.0), (3, 400, 6.0, 1.5), (2, 300, 5.0, 0.0)],
)
def test_placements_keep_the_properties_of_the_old_process(seed, dim, n, spacing, min_sep):
    world = World(dim=dim)
    pos = random_connected(n, world, np.random.default_rng(seed), spacing, min_sep)
    _check(pos, world, n, spacing, min_sep)
    assert np.allclose(pos[0], 0.0)  # grown from the centre


@pytest.mark.parametrize("seed", range(3))
def test_placements_among_walls_are_free_and_connected_around_them(tmp_path, seed):
    world = _walls(tmp_path)
    pos = random_connected(300, world, np.random.default_rng(seed), 4.0, 1.0, center=[20.0, 20.0])
    _check(pos, world, 300, 4.0, 1.0)


def _stats(pos: np.ndarray, spacing: float) -> np.ndarray:
    nearest, _ = cKDTree(pos).query(pos, k=2)
    spread = np.sqrt(((pos - pos.mean(axis=0)) ** 2).sum(axis=1).mean())
    degree = 2 * len(pairs_within(pos, spacing)) / len(pos)
    return np.array([spread, nearest[:, 1].mean(), degree])


@pytest.mark.slow
def test_statistics_match_the_one_at_a_time_process():
    """Spread, nearest-neighbour distance and degree agree with the reference's."""
    n, spacing, min_sep, seeds = 400, 8.0, 2.0, range(10)
    new = np.array([
        _stats(random_connected(n, World(dim=2), np.random.default_rng(s), spacing, min_sep),
               spacing)
        for s in seeds
    ])  # fmt: skip
    old = np.array([
        _stats(reference(n, World(dim=2), np.random.default_rng(100 + s), spacing, min_sep),
               spacing)
        for s in seeds
    ])  # fmt: skip
    se = np.sqrt(new.var(axis=0, ddof=1) / len(new) + old.var(axis=0, ddof=1) / len(old))
    diff = np.abs(new.mean(axis=0) - old.mean(axis=0))
    assert (diff < 4 * se + 0.01 * old.mean(axis=0)).all(), (new.mean(0), old.mean(0), se)


def test_a_team_that_cannot_fit_is_refused_quickly():
    world = World(dim=2, bounds_m=np.array([[-5.0, -5.0], [5.0, 5.0]]))
    start = time.perf_counter()
    with pytest.raises(ValueError, match="could not place robot .* of 500: no free space"):
        random_connected(500, world, np.random.default_rng(0), 3.0, 1.0)
    assert time.perf_counter() - start < 10


def test_large_teams_are_placed_in_n_log_n():
    """20,000 robots: seconds (the one-at-a-time process took over 10 minutes for 10,000)."""
    start = time.perf_counter()
    pos = random_connected(20_000, World(dim=2), np.random.default_rng(1), 8.0, 2.0)
    assert time.perf_counter() - start < 60
    _check(pos, World(dim=2), 20_000, 8.0, 2.0)


def test_placement_is_determined_by_the_seed():
    a = random_connected(2_000, World(dim=2), np.random.default_rng(5), 8.0, 2.0)
    b = random_connected(2_000, World(dim=2), np.random.default_rng(5), 8.0, 2.0)
    c = random_connected(2_000, World(dim=2), np.random.default_rng(6), 8.0, 2.0)
    assert np.array_equal(a, b) and not np.array_equal(a, c)


def _first_come_by_loop(k: int, pairs: np.ndarray) -> np.ndarray:
    keep = np.ones(k, dtype=bool)
    partners = {j: [] for j in range(k)}
    for i, j in np.sort(pairs, axis=1):
        partners[int(j)].append(int(i))
    for j in range(k):
        keep[j] = not any(keep[i] for i in partners[j])
    return keep


@pytest.mark.parametrize("seed", range(20))
def test_first_come_equals_placing_one_at_a_time(seed):
    rng = np.random.default_rng(seed)
    k = int(rng.integers(2, 60))
    pairs = pairs_within(rng.random((k, 2)) * 3.0, 0.6)
    keep, decided = _first_come(k, pairs, rounds=100)
    assert decided == k
    assert np.array_equal(keep, _first_come_by_loop(k, pairs))
    keep, decided = _first_come(k, pairs, rounds=1)  # few rounds: exact on a prefix
    assert np.array_equal(keep[:decided], _first_come_by_loop(k, pairs)[:decided])
