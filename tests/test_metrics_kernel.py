"""The per-step team metrics in one compiled call against the reference.

:func:`tether.sim.team_metrics` with numba loaded and a small team takes components,
lambda2, the shortest link and the close pairs from
:func:`tether.graph.metrics_kernels.team_metrics_kernel`. Counts and lengths must be
identical to the numpy/scipy reference (``TETHER_JIT=0``: scipy components, k-d tree
pairs, ``numpy.linalg.norm``, ``numpy.linalg.eigh``), lambda2 included (numba's ``eigh``
calls LAPACK's ``dsyevd`` as numpy's does), and lambda2 exactly 0 for a disconnected
graph. 2-D and 3-D teams, with and without collisions, with a fixed node (a base
station) in the graph, degenerate teams.
"""

from __future__ import annotations

import numpy as np
import pytest

from tether import jit
from tether.sensing import SensorModel, sense
from tether.sensing.robots import observation_from_pairs
from tether.sim import team_metrics

pytest.importorskip("numba")
import numba  # noqa: E402, F401  (the compiled metrics run once numba is loaded)


def _both(positions: np.ndarray, obs, collision_m: float):  # noqa: ANN001, ANN202
    with jit.using(False):
        ref = team_metrics(3, 1.5, positions, obs, collision_m)
    with jit.using(True):
        fast = team_metrics(3, 1.5, positions, obs, collision_m)
    return fast, ref


def _same(fast, ref) -> None:  # noqa: ANN001
    assert fast == ref  # every field, bit for bit
    for name in ("n_components", "n_links", "collisions"):
        assert type(getattr(fast, name)) is int, name
    assert type(fast.min_distance_m) is float and type(fast.lambda2) is float


@pytest.mark.parametrize("seed", range(16))
@pytest.mark.parametrize("dim", [2, 3])
def test_compiled_metrics_match_the_reference(seed: int, dim: int) -> None:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 120))
    spread = float(rng.choice([6.0, 14.0]))  # dense teams (collisions) and sparse ones
    pos = rng.uniform(0.0, spread * n ** (1 / dim), (n, dim))
    sensor = SensorModel(15.0, body_radius_m=0.5, radial_error_m=0.3, angular_error_rad=0.1)
    with jit.using(False):
        obs = sense(pos, sensor, rng)
    fast, ref = _both(pos, obs, float(rng.choice([0.0, 1.0, 4.0])))
    _same(fast, ref)
    if ref.n_components > 1:
        assert fast.lambda2 == 0.0


def test_compiled_metrics_with_a_fixed_node_and_degenerate_teams() -> None:
    rng = np.random.default_rng(3)
    robots = rng.uniform(0.0, 30.0, (12, 2))
    nodes = np.vstack([robots, [[15.0, 15.0]]])  # a base station as node 12
    pairs = [(i, 12) for i in range(0, 12, 2)] + [(i, i + 1) for i in range(11)]
    obs = observation_from_pairs(nodes, np.array(pairs))
    _same(*_both(robots, obs, 2.0))
    for pos in (np.zeros((0, 2)), np.zeros((1, 3)), np.array([[0.0, 0.0], [100.0, 0.0]])):
        obs = observation_from_pairs(pos, np.empty((0, 2), np.intp))
        _same(*_both(pos, obs, 1.0))
    at_limit = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [5.0, 0.0]])  # exactly 1 m apart
    obs = observation_from_pairs(at_limit, np.array([[0, 1], [1, 2], [1, 3]]))
    fast, ref = _both(at_limit, obs, 1.0)
    _same(fast, ref)
    assert ref.collisions == 2  # "closer than" includes the distance itself, as the k-d tree


def test_an_unchanged_graph_reuses_its_values_and_a_changed_one_does_not() -> None:
    """The graph cache: the same links give the same lambda2 without solving again."""
    rng = np.random.default_rng(8)
    pos = rng.uniform(0.0, 25.0, (20, 2))
    sensor = SensorModel(15.0, body_radius_m=0.5)
    with jit.using(False):
        obs = sense(pos, sensor, rng)
    with jit.using(True):
        first = team_metrics(0, 0.0, pos, obs, 1.0)
        moved = pos + 0.01  # same links, other lengths
        again = team_metrics(1, 1.0, moved, observation_from_pairs(moved, obs.pairs), 1.0)
        fewer = observation_from_pairs(pos, obs.pairs[1:])
        other = team_metrics(2, 2.0, pos, fewer, 1.0)
    assert again.lambda2 == first.lambda2
    ref = np.linalg.eigh(_laplacian(20, obs.pairs[1:]))[0][1]
    assert other.lambda2 == max(ref, 0.0)


def _laplacian(n: int, pairs: np.ndarray) -> np.ndarray:
    lap = np.zeros((n, n))
    for i, j in pairs:
        lap[i, j] = lap[j, i] = -1.0
    lap[np.diag_indices(n)] = -lap.sum(axis=1)
    return lap
