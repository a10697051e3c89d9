"""The compiled A* (``paths/astar_kernels.py``) returns the reference's paths exactly.

Random grids with many equal-cost paths exercise the tie-breaking (a heap that popped
equal ``f`` in another order, or a heuristic with other bits, picks another path of
the same cost); the town's planning grid is the campaign's real case.
"""

from __future__ import annotations

import numpy as np
import pytest

from tether import jit
from tether.paths.astar import astar_grid, plan_path, planning_grid
from tether.world.scenes import make_scene

pytestmark = pytest.mark.skipif(not jit.available(), reason="needs numba")


def _both(free: np.ndarray, s: tuple, g: tuple, **kw: str) -> tuple:
    with jit.using(False):
        ref = astar_grid(free, s, g, **kw)
    with jit.using(True):
        fast = astar_grid(free, s, g, **kw)
    return ref, fast


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("connectivity", ["full", "face"])
@pytest.mark.parametrize("heuristic", ["octile", "euclidean"])
def test_same_path_as_the_reference_on_random_grids(
    dim: int, connectivity: str, heuristic: str
) -> None:  # noqa: E501
    rng = np.random.default_rng(dim * 10 + len(connectivity) + len(heuristic))
    found = 0
    for _ in range(40):
        shape = tuple(int(x) for x in rng.integers(3, 22, dim))
        free = rng.random(shape) > rng.uniform(0.0, 0.4)
        s = tuple(int(x) for x in rng.integers(0, shape))
        g = tuple(int(x) for x in rng.integers(0, shape))
        ref, fast = _both(free, s, g, connectivity=connectivity, heuristic=heuristic)
        assert (ref is None) == (fast is None)
        if ref is not None:
            found += 1
            np.testing.assert_array_equal(fast, ref)
    assert found >= 10  # the comparison saw real paths, not only unreachable goals


def test_open_grid_ties_and_the_growing_heap() -> None:
    # an empty 3-D box: thousands of equal-cost paths and a heap far past its first size
    free = np.ones((30, 30, 12), dtype=bool)
    ref, fast = _both(free, (0, 0, 0), (29, 17, 11), heuristic="euclidean")
    np.testing.assert_array_equal(fast, ref)


def test_the_town_planning_grid() -> None:
    world = make_scene("town")
    plan = planning_grid(world, cell_m=0.75)
    rng = np.random.default_rng(3)
    lo, hi = world.bounds_m
    for _ in range(4):
        a, b = rng.uniform(lo, hi), rng.uniform(lo, hi)
        with jit.using(False):
            ref = plan_path(world, a, b, cell_m=0.75, planning=plan)
        with jit.using(True):
            fast = plan_path(world, a, b, cell_m=0.75, planning=plan)
        assert (ref is None) == (fast is None)
        if ref is not None:
            np.testing.assert_array_equal(fast, ref)
