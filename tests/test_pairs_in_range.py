"""The weights' pair search, exactly
(:func:`~tether.continuous.connectivity.pair_kernels.pairs_in_range`).

Above ``BRUTE_MAX_N`` robots it has two cube searches: every cube in one array (compact
teams) and sorted cube codes (spread-out teams). Both must give brute force's pairs,
``||q_i - q_j|| < r`` with numpy's norm, in lexicographic order, including pairs at
(or within rounding of) the range, where the dense search decides without a square
root only away from ``r * r``.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("numba")

from tether.continuous.connectivity.pair_kernels import BRUTE_MAX_N, pairs_in_range  # noqa: E402


def brute(q: np.ndarray, r: float) -> np.ndarray:
    i, j = np.triu_indices(len(q), 1)
    keep = np.sqrt(((q[i] - q[j]) ** 2).sum(axis=1)) < r
    return np.column_stack([i[keep], j[keep]])


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("spread", [False, True])
def test_both_cube_searches_equal_brute_force(seed: int, spread: bool) -> None:
    rng = np.random.default_rng(seed)
    n = BRUTE_MAX_N + 200
    dim = 3 if seed % 2 else 2
    q = rng.uniform(0, 40.0 if dim == 2 else 20.0, (n, dim))
    if spread:  # clusters far apart: too many cubes for one array
        q += rng.integers(0, 4, (n, 1)) * 1e4
    got = pairs_in_range(np.ascontiguousarray(q), 6.0)
    want = brute(q, 6.0)
    assert len(want) > n // 2  # enough pairs to mean something
    assert np.array_equal(got, want)


@pytest.mark.parametrize("spread", [False, True])
def test_pairs_at_the_range_within_rounding(spread: bool) -> None:
    """A lattice of spacing exactly ``r`` and points moved by a few ulps around it."""
    r = 6.0
    cells = np.argwhere(np.ones((8, 6, 4), dtype=bool)).astype(float)
    rng = np.random.default_rng(3)
    scale = r * (1.0 + rng.choice([-3e-16, -1e-15, 0.0, 1e-15, 3e-16], size=(len(cells), 1)))
    q = cells * scale + (0.1 if spread else 0.0)
    if spread:
        q[::2] += 1e5
    got = pairs_in_range(np.ascontiguousarray(q), r)
    assert np.array_equal(got, brute(q, r))
    exact = cells * r
    assert np.array_equal(pairs_in_range(exact, r), brute(exact, r))
    assert len(pairs_in_range(exact, r)) == 0 or np.all(
        np.linalg.norm(
            exact[pairs_in_range(exact, r)[:, 0]] - exact[pairs_in_range(exact, r)[:, 1]], axis=1
        )
        < r
    )


@pytest.mark.parametrize("seed", range(4))
def test_small_teams_brute_force_at_the_range_within_rounding(seed: int) -> None:
    """Below ``BRUTE_MAX_N`` robots: a lattice of spacing ``r`` moved by a few ulps (the
    root-free test must decide pairs at ``r`` as the root does), random teams, and a
    robot at NaN (never a pair)."""
    r = 6.0
    rng = np.random.default_rng(seed)
    cells = np.argwhere(np.ones((5, 4, 3), dtype=bool)).astype(float)
    assert len(cells) <= BRUTE_MAX_N
    scale = r * (1.0 + rng.choice([-3e-16, -1e-15, 0.0, 1e-15, 3e-16], size=(len(cells), 1)))
    for q in (cells * scale, cells * r, rng.uniform(0.0, 15.0, (BRUTE_MAX_N, 3))):
        got = pairs_in_range(np.ascontiguousarray(q), r)
        assert np.array_equal(got, brute(q, r))
    q = rng.uniform(0.0, 15.0, (40, 3))
    q[7] = np.nan
    got = pairs_in_range(q, r)
    assert np.array_equal(got, brute(q, r)) and not np.any(got == 7)
