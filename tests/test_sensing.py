from __future__ import annotations

import numpy as np
import pytest

from tether.geometry import angle_between
from tether.graph import is_connected, pairs_within
from tether.sensing import SensorModel, sense, sensed_pairs
from tether.world.grid import OccupancyGrid
from tether.world.world import World


def test_middle_robot_hides_the_ends():
    pos = np.array([[0.0, 0.0], [5.0, 0.0], [10.0, 0.0]])
    sensor = SensorModel(range_m=15.0, body_radius_m=0.5)
    assert {tuple(p) for p in sensed_pairs(pos, sensor)} == {(0, 1), (1, 2)}
    off_line = pos + np.array([[0, 0], [0, 0.6], [0, 0]])  # body no longer on the segment
    assert len(sensed_pairs(off_line, sensor)) == 3
    no_occ = SensorModel(range_m=15.0, body_radius_m=0.5, occlusion=False)
    assert len(sensed_pairs(pos, no_occ)) == 3


@pytest.mark.parametrize("dim", [2, 3])
def test_occlusion_never_changes_connectivity(dim):
    """Paper, remark after Theorem 1: occlusion removes links, never connectivity."""
    sensor = SensorModel(range_m=4.0, body_radius_m=0.4)
    checked = 0
    for seed in range(150):
        rng = np.random.default_rng(seed)
        pos = rng.uniform(0, 8 if dim == 2 else 5, (30, dim))
        visible = sensed_pairs(pos, sensor)
        in_range = pairs_within(pos, sensor.range_m)
        assert len(visible) <= len(in_range)
        checked += len(in_range) - len(visible)
        assert is_connected(30, visible) == is_connected(30, in_range)
    assert checked > 0  # occlusion actually happened


def test_obstacles_block_line_of_sight():
    occ = np.zeros((20, 20), dtype=bool)
    occ[10, 0:15] = True  # a wall at x in [10, 11)
    world = World(dim=2, grid=OccupancyGrid(occ, 1.0))
    pos = np.array([[5.0, 5.0], [15.0, 5.0], [5.0, 18.0], [15.0, 18.0]])
    pairs = {tuple(p) for p in sensed_pairs(pos, SensorModel(range_m=30.0), world)}
    assert (0, 1) not in pairs and (2, 3) in pairs and (0, 2) in pairs


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("noise", ["uniform", "bound"])
def test_measurement_errors_stay_within_bounds(dim, noise):
    sensor = SensorModel(
        range_m=15.0, radial_error_m=0.45, angular_error_rad=np.radians(12), noise=noise
    )
    rng = np.random.default_rng(3)
    lattice = np.stack(np.meshgrid(*[np.arange(4) * 3.0] * dim, indexing="ij"), -1)
    pos = lattice.reshape(-1, dim) + rng.uniform(-1, 1, (4**dim, dim))  # >= 1 m apart
    obs = sense(pos, sensor, rng)
    true = obs.true_relative
    d_err = np.linalg.norm(obs.measured, axis=1) - np.linalg.norm(true, axis=1)
    a_err = angle_between(obs.measured, true)
    assert np.all(np.abs(d_err) <= 0.45 + 1e-9)
    assert np.all(a_err <= np.radians(12) + 1e-6)
    if noise == "bound":
        np.testing.assert_allclose(np.abs(d_err), 0.45, atol=1e-9)
        np.testing.assert_allclose(a_err, np.radians(12), atol=1e-6)

    else:
        assert np.abs(d_err).max() > 0.2 and a_err.max() > np.radians(6)


def test_observation_rows_are_what_each_robot_senses():
    rng = np.random.default_rng(0)
    pos = rng.uniform(0, 10, (15, 2))
    obs = sense(pos, SensorModel(range_m=4.0, noise="none"), rng)
    for i in range(15):
        sensed = {int(b) if a == i else int(a) for a, b in obs.pairs if i in (a, b)}
        targets = obs.target[obs.indptr[i] : obs.indptr[i + 1]]
        assert set(targets.tolist()) == sensed
        np.testing.assert_allclose(obs.of(i), pos[targets] - pos[i])
