"""The cached clearance search's candidate lists give the tree search's answer, bit for bit.

:func:`tether.world.clearance_cache_kernels.segments_nearest_cached` scans a segment
nearer than ``within`` over the obstacle points it listed when it last searched it, as
long as its endpoints have moved at most ``slack``. These tests drive a team of links
through grid worlds the way a run does (small moves, in the lists' regime, then large
ones and jumps) and compare every call with the uncached tree search
(:func:`~tether.world.clearance_kernels.segments_nearest`), which the numpy reference
checks elsewhere, and with brute force; they also check that the lists were used, that
a pool too small for the lists changes nothing, and ties on a grid's faces.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("numba")

from _clearance_helpers import box_world, brute  # noqa: E402
from tether.graph.structure import pairs_within  # noqa: E402
from tether.world import clearance_cache_kernels as cc  # noqa: E402
from tether.world import clearance_kernels as ck  # noqa: E402
from tether.world.clearance import ObstacleIndex, einsum_order  # noqa: E402
from tether.world.grid import OccupancyGrid  # noqa: E402
from tether.world.world import World  # noqa: E402

WITHIN, SLACK = 1.75, 0.25


def table(index: ObstacleIndex, pool: int | None = None) -> tuple[np.ndarray, ...]:
    """A fresh kernel table of ``index`` (its default pool, or ``pool`` slots)."""
    index.kernel_grow(64)
    t = index._kernel_table(64)
    if pool is not None:  # the same table with a pool of ``pool`` slots
        slots = (np.zeros(pool, dtype=np.int64), np.zeros((pool, index.dim)))
        t = (*t[:8], *slots, np.zeros(2, dtype=np.int64))
    return t


def cached(index: ObstacleIndex, t: tuple, a: np.ndarray, b: np.ndarray, keys: np.ndarray):
    return cc.segments_nearest_cached(*index._kernel_tree, a, b, WITHIN, keys, SLACK, *t,
                                      *index._kernel_field, einsum_order())[:3]  # fmt: skip


def uncached(index: ObstacleIndex, a: np.ndarray, b: np.ndarray):
    return ck.segments_nearest(*index._kernel_tree, a, b, WITHIN, *index._kernel_field,
                               einsum_order())  # fmt: skip


def drive(dim: int, seed: int, pool: int | None = None, steps: int = 60) -> int:
    """Move a team through a box world; every call as the uncached search. Returns how
    many segments had a candidate list after the calls (summed over the calls)."""
    rng = np.random.default_rng(seed)
    world = box_world(rng, dim, boxes=8)
    hi = np.array([20.0, 20.0, 8.0])[:dim]
    index = ObstacleIndex.from_world(world)
    t = table(index, pool)
    q = rng.uniform(0.5, hi - 0.5, (24, dim))
    listed = 0
    for step in range(steps):
        # mostly moves well below the slack (lists scanned), some around it, some jumps
        scale = [0.01, 0.04, 0.1, 0.3][step % 4]
        q = np.clip(q + rng.normal(0.0, scale, q.shape), 0.3, hi - 0.3)
        if step % 15 == 14:
            q[rng.integers(len(q))] = rng.uniform(0.5, hi - 0.5)
        pairs = pairs_within(q, 6.0)
        a, b = q[pairs[:, 0]].copy(), q[pairs[:, 1]].copy()
        keys = pairs[:, 0].astype(np.int64) * len(q) + pairs[:, 1]
        got = cached(index, t, a, b, keys)
        want = uncached(index, a, b)
        for x, y in zip(got, want, strict=True):
            np.testing.assert_array_equal(x, y)
        near = np.isfinite(want[0])
        np.testing.assert_allclose(want[0][near], brute(index.points, a[near], b[near]),
                                   atol=1e-9)  # fmt: skip
        listed += int(np.sum((t[6] >= 0) & (t[7] == t[10][1])))  # valid lists
    return listed


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("seed", range(4))
def test_lists_give_the_tree_search_answer(dim: int, seed: int) -> None:
    assert drive(dim, seed) > 0  # the lists were made (and so scanned on small moves)


@pytest.mark.parametrize("pool", [0, 40, 300])
def test_a_pool_too_small_for_the_lists_changes_nothing(pool: int) -> None:
    # pool 0: no list fits; 40: some fit, and a full pool is emptied again and again
    drive(3, 11, pool=pool, steps=40)


def test_ties_on_a_face_go_to_the_lowest_point_index() -> None:
    """A segment parallel to a box face is equally near many face points; moving it
    along the face keeps the tie, and the list must pick the tree's point."""
    occ = np.zeros((40, 40), dtype=bool)
    occ[10:30, 10:20] = True  # a face at y = 10 m (cell centres at y = 9.75 m)
    index = ObstacleIndex.from_world(World(dim=2, grid=OccupancyGrid(occ, 0.5, np.zeros(2))))
    t = table(index)
    keys = np.array([7], dtype=np.int64)
    for dx in np.linspace(0.0, 0.2, 9):  # within the slack: scanned from the list
        a, b = np.array([[9.0 + dx, 11.0]]), np.array([[14.0 + dx, 11.0]])
        got, want = cached(index, t, a, b, keys), uncached(index, a, b)
        for x, y in zip(got, want, strict=True):
            np.testing.assert_array_equal(x, y)
        assert np.isfinite(got[0][0])
    assert t[6][t[0] == 7][0] >= 0 and t[7][t[0] == 7][0] == t[10][1]  # listed
