"""Incremental map exchange (only newly sensed cells in unchanged groups) = whole-map merges."""

from __future__ import annotations

import numpy as np
import pytest

from tether.recurrent.exploration.knowledge import Knowledge


def _partition(rng: np.random.Generator, n: int) -> tuple[list[list[int]], list[bool]]:
    labels = rng.integers(0, 3 if rng.random() < 0.5 else 6, size=n)
    groups = [np.flatnonzero(labels == k).tolist() for k in range(6)]
    groups = [g for g in groups if g]
    bs = int(rng.integers(-1, len(groups)))  # -1: no group holds the BS
    with_bs = [k == bs for k in range(len(groups))]
    if rng.random() < 0.3:  # a call that leaves some robots out (the BS map may grow meanwhile)
        keep = rng.random(len(groups)) < 0.5
        groups = [g for g, k in zip(groups, keep, strict=True) if k]
        with_bs = [b for b, k in zip(with_bs, keep, strict=True) if k]
    return groups, with_bs


@pytest.mark.parametrize("seed", range(20))
def test_incremental_exchange_equals_full_merge(seed: int) -> None:
    rng = np.random.default_rng(seed)
    shape, n = (23, 31), 6
    fast = Knowledge(shape, n)
    ref = Knowledge(shape, n, incremental=False)
    taken = 0
    original = fast._exchange_new

    def counted(members: list[int], bs: bool) -> None:
        nonlocal taken
        taken += 1
        original(members, bs)

    fast._exchange_new = counted  # type: ignore[method-assign]
    groups, with_bs = _partition(rng, n)
    for _ in range(150):
        for r in np.flatnonzero(rng.random(n) < 0.6):
            # a patch around a random cell (repeated and already known cells included)
            c = rng.integers(0, shape[0] * shape[1])
            cells = np.clip(c + rng.integers(-40, 40, size=int(rng.integers(0, 30))), 0, None)
            cells = np.minimum(cells, shape[0] * shape[1] - 1).astype(np.intp)
            fast.observe(int(r), cells)
            ref.observe(int(r), cells)
        if rng.random() < 0.25:  # the groups change now and then
            groups, with_bs = _partition(rng, n)
        fast.exchange(groups, with_bs)
        ref.exchange(groups, with_bs)
        assert np.array_equal(fast.local_known, ref.local_known)
        assert np.array_equal(fast.global_known, ref.global_known)
        assert fast.global_version == ref.global_version
        assert np.array_equal(fast._seen, ref._seen)
    assert taken > 10  # the incremental path ran


@pytest.mark.parametrize("incremental", [True, False])
def test_member_behind_the_bs_map_gets_all_of_it(incremental: bool) -> None:
    """A robot whose group did not change but whose BS map is old gets the whole BS map."""
    k = Knowledge((4, 5), 2, incremental=incremental)
    k.observe(0, np.array([0]))
    k.exchange([[0]], [True])  # robot 0 alone with the BS
    k.observe(1, np.array([7]))
    k.exchange([[1]], [True])  # robot 0 left out; the BS learns cell 7 from robot 1
    k.observe(0, np.array([3]))
    k.exchange([[0]], [True])  # robot 0's group is unchanged, but its BS map is old
    assert k.local_known[0].reshape(-1)[[0, 3, 7]].all()
    assert np.array_equal(k.local_known[0], k.global_known)
