"""A small 2-D team sensed in one compiled call against the split compiled path.

:func:`tether.sensing.robots_kernels.sense_noisy_kernel` (pairs, occlusion, CSR, the
sensor's draws, ``cos``/``sin`` of the angular errors, the noise) must give the
observation of :func:`tether.sensing.sense`'s split path (pairs kernel, draws kernel,
numpy's ``cos``/``sin``, noise kernel) bit for bit, and leave the random generator in
the same state (the next draws are the same). The split path itself is compared with
the numpy reference in ``test_sensing_kernels.py``.
"""

from __future__ import annotations

import numpy as np
import pytest

from tether import jit
from tether.sensing import SensorModel, sense

pytest.importorskip("numba")

from tether.sensing import robots_kernels  # noqa: E402  (loads numba)


def _observe(fused: bool, noise: str, body_m: float, seed: int, monkeypatch) -> list:  # noqa: ANN001
    monkeypatch.setattr(robots_kernels, "numpy_trig_is_libm", lambda: fused)
    rng = np.random.default_rng(seed)
    sensor = SensorModel(15.0, body_radius_m=body_m, radial_error_m=0.45,
                         angular_error_rad=0.2, noise=noise)  # fmt: skip
    out = []
    with jit.using(True):
        for n in (2, 3, 20, 45, 1, 0):
            pos = rng.uniform(0.0, 30.0, (n, 2))
            if n == 3:
                pos[:] = pos[0]  # coincident robots: zero relatives
            obs = sense(pos, sensor, rng)
            out += [obs.pairs, obs.indptr, obs.target, obs.measured, obs.true_relative]
    return [*out, rng.random(3)]  # the generator's state afterwards


@pytest.mark.parametrize("noise", ["uniform", "bound", "none"])
@pytest.mark.parametrize("body_m", [0.5, 0.0])
@pytest.mark.parametrize("seed", range(3))
def test_one_call_is_the_split_path(noise: str, body_m: float, seed: int, monkeypatch) -> None:  # noqa: ANN001
    split = _observe(False, noise, body_m, seed, monkeypatch)
    fused = _observe(True, noise, body_m, seed, monkeypatch)
    for a, b in zip(split, fused, strict=True):
        assert a.dtype == b.dtype
        np.testing.assert_array_equal(b, a)


def test_the_trig_check_holds_when_it_says_so() -> None:
    """Where the check says numpy's ``cos``/``sin`` are the C library's, they agree on
    fresh arguments too (angular errors, and wider)."""
    x = np.random.default_rng(11).uniform(-1.6, 1.6, 100_000)
    c, s = robots_kernels._cos_sin_kernel(x)
    same = np.array_equal(c, np.cos(x)) and np.array_equal(s, np.sin(x))
    assert robots_kernels.numpy_trig_is_libm() == same


def test_occlusion_kernel_with_ties_and_collinear_robots() -> None:
    """Integer positions (equal distances, robots on one line): the same booleans as
    the numpy reference, 2-D and 3-D."""
    from tether.graph import pairs_within
    from tether.sensing.robots import _occluded

    rng = np.random.default_rng(4)
    for t in range(400):
        dim = 2 + t % 2
        pos = np.round(rng.uniform(0.0, 12.0, (int(rng.integers(3, 40)), dim)))
        pairs = pairs_within(pos, 6.0)
        ref = _occluded(pos, pairs, 0.6)
        np.testing.assert_array_equal(
            robots_kernels.occluded_kernel(pos, pairs.astype(np.int64), 0.6), ref
        )
