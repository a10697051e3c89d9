"""Eq. (1) of the recurrent-connectivity paper, by hand: ``U(f) = g(f) / min_j d(p_j, f)^2``."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from tether.recurrent.replanning import frontier_utilities


def test_utility_is_the_gain_over_the_squared_distance_to_the_nearest_ready_robot() -> None:
    # vertices 0..4; frontiers 1, 2, 3, 4; two ready robots (rows of dist)
    graph = SimpleNamespace(frontiers=np.array([1, 2, 3, 4]),
                            gain=np.array([0.0, 40.0, 30.0, 12.0, 0.0]))  # fmt: skip
    dist = np.array([[0.0, 2.0, 5.0, 0.5, 1.0], [0.0, 4.0, 3.0, np.inf, 9.0]])
    got = frontier_utilities(graph, dist)
    assert got == pytest.approx({1: 40.0 / 2.0**2, 2: 30.0 / 3.0**2, 3: 12.0 / 1.0})
    # below one cell counts as one cell; a frontier without gain or excluded is left out
    assert 4 not in got
    assert set(frontier_utilities(graph, dist, exclude={1})) == {2, 3}
    unreachable = frontier_utilities(graph, np.full((1, 5), np.inf))
    assert unreachable == {}
