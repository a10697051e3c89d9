"""The compiled sensing against the numpy reference, bit for bit.

:mod:`tether.sensing.robots_kernels` repeats the reference's arithmetic term for term
and takes its random numbers from the same ``Generator`` draws in the same order, so
pairs, occlusion, CSR order and noisy measurements are identical (Kerestecioglu and
Cezayirli's occlusion, Fig. 3, and bounded errors, Fig. 1), in 2-D and 3-D, with
uniform and bound noise; and a whole ``silent`` run ends at the same positions.
"""

from __future__ import annotations

import numpy as np
import pytest

from tether import jit
from tether.graph import pairs_within
from tether.sensing import SensorModel, sense
from tether.sensing.robots import _occluded
from tether.world.grid import OccupancyGrid
from tether.world.world import World

pytest.importorskip("numba")


def _team(seed: int, dim: int) -> tuple[np.random.Generator, np.ndarray]:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 80))
    side = 12.0 * n ** (1 / dim)
    return rng, rng.uniform(0.0, side, (n, dim))


@pytest.mark.parametrize("seed", range(10))
@pytest.mark.parametrize("dim", [2, 3])
def test_occlusion_kernel_is_exact(seed: int, dim: int) -> None:
    from tether.sensing.robots_kernels import occluded_kernel

    _, pos = _team(seed, dim)
    pairs = pairs_within(pos, 15.0)
    for radius in (0.5, 2.0):
        ref = _occluded(pos, pairs, radius)
        fast = occluded_kernel(pos, pairs.astype(np.int64), radius)
        np.testing.assert_array_equal(fast, ref)


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("noise", ["none", "uniform", "bound"])
def test_sense_kernels_are_bit_identical(seed: int, dim: int, noise: str) -> None:
    _, pos = _team(seed, dim)
    sensor = SensorModel(15.0, body_radius_m=1.0, radial_error_m=0.45,
                         angular_error_rad=np.radians(12), noise=noise)  # fmt: skip
    with jit.using(False):
        ref = sense(pos, sensor, np.random.default_rng(seed))
    with jit.using(True):
        fast = sense(pos, sensor, np.random.default_rng(seed))
    for name in ("pairs", "indptr", "target", "measured", "true_relative"):
        a, b = getattr(fast, name), getattr(ref, name)
        assert a.shape == b.shape, name
        assert a.dtype == b.dtype, name
        np.testing.assert_array_equal(a, b, err_msg=name)


def test_sense_kernels_on_degenerate_teams() -> None:
    sensor = SensorModel(5.0, body_radius_m=0.5, radial_error_m=0.1, angular_error_rad=0.1)
    for pos in (np.zeros((0, 2)), np.zeros((1, 2)), np.array([[0.0, 0], [100.0, 0]]),
                np.array([[0.0, 0, 0], [1.0, 0, 0], [2.0, 0, 0]])):  # fmt: skip
        with jit.using(False):
            ref = sense(pos, sensor, np.random.default_rng(1))
        with jit.using(True):
            fast = sense(pos, sensor, np.random.default_rng(1))
        np.testing.assert_array_equal(fast.pairs, ref.pairs)
        np.testing.assert_array_equal(fast.indptr, ref.indptr)
        np.testing.assert_array_equal(fast.measured, ref.measured)


@pytest.mark.parametrize("noise", ["uniform", "bound"])
def test_large_team_and_obstacles_take_the_split_path_bit_identically(noise: str) -> None:
    rng = np.random.default_rng(5)
    big = rng.uniform(0.0, 120.0, (400, 2))  # above KERNEL_PAIRS_MAX_N: k-d tree + kernels
    occ = np.zeros((40, 40), dtype=bool)
    occ[20, 0:30] = True  # a wall: line of sight first, then occlusion and CSR kernels
    walled = World(dim=2, grid=OccupancyGrid(occ, 1.0))
    small = rng.uniform(0.5, 39.5, (40, 2))
    sensor = SensorModel(15.0, body_radius_m=1.0, radial_error_m=0.3,
                         angular_error_rad=0.1, noise=noise)  # fmt: skip
    for pos, world in ((big, None), (small, walled)):
        with jit.using(False):
            ref = sense(pos, sensor, np.random.default_rng(9), world)
        with jit.using(True):
            fast = sense(pos, sensor, np.random.default_rng(9), world)
        for name in ("pairs", "indptr", "target", "measured", "true_relative"):
            np.testing.assert_array_equal(getattr(fast, name), getattr(ref, name), name)


@pytest.mark.parametrize("bitgen", ["PCG64", "MT19937", "Philox", "SFC64"])
def test_compiled_draws_are_the_generators(bitgen: str) -> None:
    """The errors and coin flips drawn in compiled code are numpy's ``uniform`` and
    ``choice([-1, 1])`` draws: the same values and the same stream afterwards, for odd
    counts (a buffered half word of ``next_uint32``) and with numpy draws between."""
    from tether.sensing.draws_kernels import NOISE_CODES, bitgen_addresses, sensor_errors_kernel

    make = getattr(np.random, bitgen)
    for seed in range(6):
        a, b = np.random.Generator(make(seed)), np.random.Generator(make(seed))
        for k in (0, 1, 2, 3, 7, 138, 241, 1):
            for noise in ("uniform", "bound"):
                for rng in (a, b):
                    rng.uniform(-1.0, 1.0, seed % 3)  # doubles between the draws
                e_r, e_a, flip = sensor_errors_kernel(
                    k, NOISE_CODES[noise], 0.45, 0.2, k % 2 == 1, bitgen_addresses(a)
                )
                if noise == "uniform":
                    ref_r, ref_a = b.uniform(-0.45, 0.45, size=k), b.uniform(-0.2, 0.2, size=k)
                else:
                    ref_r = 0.45 * b.choice([-1.0, 1.0], size=k)
                    ref_a = 0.2 * b.choice([-1.0, 1.0], size=k)
                np.testing.assert_array_equal(e_r, ref_r)
                np.testing.assert_array_equal(e_a, ref_a)
                ref_flip = b.choice([-1.0, 1.0], size=k) if k % 2 == 1 else np.empty(0)
                np.testing.assert_array_equal(np.array([-1.0, 1.0])[flip], ref_flip)
        assert a.integers(0, 2**62) == b.integers(0, 2**62)
        assert a.random() == b.random()
    none = sensor_errors_kernel(5, NOISE_CODES["none"], 0.45, 0.2, True, bitgen_addresses(a))
    assert not any(x.any() for x in none)
    assert a.random() == b.random()  # "none" draws nothing
