"""The compiled ray walk of the depth sensor against the numpy reference (same arrays)."""

from __future__ import annotations

import numpy as np
import pytest

from tether import jit
from tether.sensing.depth import DepthSensor, cast_rays

numba = pytest.importorskip("numba")  # jit.warm(): numba loaded


@pytest.mark.parametrize("seed", range(12))
def test_scan_kernel_matches_reference(seed: int) -> None:
    rng = np.random.default_rng(seed)
    shape = (int(rng.integers(20, 120)), int(rng.integers(20, 120)))
    occ = rng.random(shape) < (0.01, 0.05, 0.2)[seed % 3]
    k = int(rng.integers(1, 15))
    origins = rng.uniform(-3, 3, size=(k, 2)) + rng.uniform(0, 1, size=(k, 2)) * shape
    headings = rng.uniform(-4, 4, size=k)
    full = rng.random(k) < 0.4
    sensor = DepthSensor(float(rng.uniform(20, 120)), float(rng.uniform(5, 60)), 1.0)
    with jit.using(False):
        want = sensor.scan(occ, origins, headings, full)
    with jit.using(True):
        assert jit.warm()
        got = sensor.scan(occ, origins, headings, full)
    assert len(got) == len(want)
    for a, b in zip(got, want, strict=True):
        assert a.dtype == b.dtype and np.array_equal(a, b)


def test_scan_kernel_stops_at_the_first_hit() -> None:
    """A wall across the ray: the wall cell is seen, nothing behind it (both paths)."""
    occ = np.zeros((30, 5), dtype=bool)
    occ[10, :] = True
    for kernel in (False, True):
        with jit.using(kernel):
            (cells,) = cast_rays(occ, np.array([[2.5, 2.5]]), np.array([0.0]), 0.0, 20.0, 1.0)
        xs = np.unique(cells // 5)
        assert xs.max() == 10 and xs.tolist() == list(range(2, 11))
