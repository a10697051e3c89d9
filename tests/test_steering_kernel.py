"""The compiled constrained steps against the numpy reference.

Both evaluate constraints (1)-(2) of Kerestecioglu and Cezayirli (Sec. IV) with the same
arithmetic; only ``arccos``/``cos`` come from different libraries, so the steps agree to
1e-12, on random teams in 2-D and 3-D, with and without the direction search, the
minimum separation and a speed limit.
"""

from __future__ import annotations

import numpy as np
import pytest

from tether import jit
from tether.sensing import Observation, SensorModel, sense
from tether.silent.steering import constrained_steps, desired_steps

pytest.importorskip("numba")


def _random_observation(seed: int, dim: int) -> tuple[np.random.Generator, int, Observation]:
    """A random team of 1-59 robots sensed with the silent paper's error bounds."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 60))
    pos = rng.uniform(0.0, 30.0, (n, dim))
    sensor = SensorModel(15.0, body_radius_m=0.5, radial_error_m=0.45,
                         angular_error_rad=np.radians(12))  # fmt: skip
    obs = sense(pos, sensor, rng)
    return rng, n, obs


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("dim", [2, 3])
def test_kernel_matches_reference(seed: int, dim: int) -> None:
    rng, n, obs = _random_observation(seed, dim)
    desired = rng.normal(size=(n, dim)) * rng.uniform(0.0, 3.0, (n, 1))
    desired[rng.random(n) < 0.1] = 0.0  # robots that do not want to move
    observer = obs.observer()
    for search in (False, True):
        for min_sep, max_step in ((0.0, np.inf), (1.0, 0.8)):
            kw = dict(d_max_m=15.0, radial_error_m=0.45, angular_error_rad=np.radians(12),
                      min_separation_m=min_sep, max_step_m=max_step,
                      search_directions=search)  # fmt: skip
            with jit.using(False):
                ref = constrained_steps(desired, obs.measured, observer, **kw)
            with jit.using(True):
                fast = constrained_steps(desired, obs.measured, observer, **kw)
            np.testing.assert_allclose(fast, ref, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("dim", [2, 3])
def test_desired_distance_kernel_is_bit_identical(seed: int, dim: int) -> None:
    rng, n, obs = _random_observation(seed, dim)
    with jit.using(False):
        ref = desired_steps(obs.measured, obs.observer(), n, gamma=0.3, d0_m=7.0)
    with jit.using(True):
        fast = desired_steps(obs.measured, obs.observer(), n, gamma=0.3, d0_m=7.0)
    np.testing.assert_array_equal(fast, ref)


@pytest.mark.parametrize("seed", range(12))
def test_pruned_kernel_matches_reference_on_crowded_teams(seed: int) -> None:
    """The direction search's pruning and the bounds skipped without ``acos`` are exact:
    crowded teams (many binding constraints), large and zero angular errors."""
    rng = np.random.default_rng(100 + seed)
    dim = 2 + seed % 2
    n = int(rng.integers(20, 120))
    pos = rng.uniform(0.0, 2.0 * n ** (1 / dim) * 3.0, (n, dim))
    ang = float(rng.choice([0.0, np.radians(12), 1.2]))
    sensor = SensorModel(15.0, body_radius_m=0.3, radial_error_m=0.45, angular_error_rad=ang)
    obs = sense(pos, sensor, rng)
    desired = rng.normal(size=(n, dim)) * rng.uniform(0.0, 6.0, (n, 1))
    for search in (False, True):
        for min_sep, max_step in ((0.0, np.inf), (1.0, 0.8), (2.5, np.inf)):
            kw = dict(d_max_m=15.0, radial_error_m=0.45, angular_error_rad=ang,
                      min_separation_m=min_sep, max_step_m=max_step,
                      search_directions=search)  # fmt: skip
            with jit.using(False):
                ref = constrained_steps(desired, obs.measured, obs.observer(), **kw)
            with jit.using(True):
                fast = constrained_steps(desired, obs.measured, obs.observer(), **kw)
            np.testing.assert_allclose(fast, ref, rtol=1e-12, atol=1e-12)


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("dim", [2, 3])
def test_team_steps_kernel_is_the_three_steps(seed: int, dim: int) -> None:
    """One call (desired steps, the leader's step, constraints) gives the steps of the
    three kernels called one by one, bit for bit, and the reference's to 1e-12."""
    from tether.silent.steering import team_steps

    rng, n, obs = _random_observation(seed, dim)
    leader = int(rng.integers(0, n))
    leader_step = rng.normal(size=dim) * 2.0
    for search in (False, True):
        for min_sep, max_step in ((0.0, np.inf), (1.0, 0.8)):
            kw = dict(d_max_m=15.0, radial_error_m=0.45, angular_error_rad=np.radians(12),
                      min_separation_m=min_sep, max_step_m=max_step,
                      search_directions=search)  # fmt: skip
            with jit.using(True):
                fused = team_steps(obs.measured, obs.indptr, leader, leader_step,
                                   gamma=0.3, d0_m=7.0, **kw)  # fmt: skip
                desired = desired_steps(obs.measured, obs.observer(), n, gamma=0.3, d0_m=7.0)
                desired[leader] = leader_step
                chained = constrained_steps(desired, obs.measured, obs.observer(), **kw)
            with jit.using(False):
                ref = team_steps(obs.measured, obs.indptr, leader, leader_step,
                                 gamma=0.3, d0_m=7.0, **kw)  # fmt: skip
            np.testing.assert_array_equal(fused, chained)
            np.testing.assert_allclose(fused, ref, rtol=1e-12, atol=1e-12)
