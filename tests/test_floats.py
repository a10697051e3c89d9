"""tether.floats: the C library's values and in-order sums, whatever numpy does on this CPU.

The compiled kernels call the C library (numba) and sum in order; the reference paths
use :mod:`tether.floats` so that both give the same bits on every machine (on AVX-512
machines numpy's own ``exp``, ``tan``, ``arccos``, ``power`` and BLAS ``dot`` do not).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tether import floats

FUNCTIONS = {
    "exp": (floats.exp, math.exp, (-30.0, 30.0)),
    "log": (floats.log, math.log, (1e-6, 50.0)),
    "cos": (floats.cos, math.cos, (-7.0, 7.0)),
    "sin": (floats.sin, math.sin, (-7.0, 7.0)),
    "tan": (floats.tan, math.tan, (-1.57, 1.57)),
    "arccos": (floats.arccos, math.acos, (-1.0, 1.0)),
}


@pytest.fixture(params=[True, False], ids=["probe", "element-by-element"])
def path(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> bool:
    """Both ways of computing: as this machine's probe decides, and forced element by element."""
    if not request.param:
        monkeypatch.setattr(floats, "numpy_is_libm", lambda name: False)
        monkeypatch.setattr(floats, "_power_is_libm", lambda: False)
    return request.param


@pytest.mark.parametrize("name", sorted(FUNCTIONS))
def test_functions_are_the_c_librarys(name: str, path: bool) -> None:
    f, libm, (lo, hi) = FUNCTIONS[name]
    x = np.random.default_rng(1).uniform(lo, hi, (50, 7))
    got = f(x)
    assert got.shape == x.shape and got.dtype == np.float64
    np.testing.assert_array_equal(got, [[libm(t) for t in row] for row in x.tolist()])


def test_special_values_are_numpys(path: bool) -> None:
    with np.errstate(all="ignore"):
        np.testing.assert_array_equal(floats.exp(np.array([1000.0, -1000.0, np.nan])),
                                      [np.inf, 0.0, np.nan])  # fmt: skip
        np.testing.assert_array_equal(floats.log(np.array([0.0, -1.0, np.inf])),
                                      [-np.inf, np.nan, np.inf])  # fmt: skip
        np.testing.assert_array_equal(floats.arccos(np.array([1.5, -1.0])), [np.nan, np.pi])
        np.testing.assert_array_equal(floats.cos(np.array([np.inf])), [np.nan])
    assert floats.exp(np.zeros((0, 3))).shape == (0, 3)
    assert float(floats.exp(0.0)) == 1.0


def test_power_is_the_c_librarys(path: bool) -> None:
    rng = np.random.default_rng(2)
    y = rng.uniform(0.0, 1.0, 300)
    for p in (1.0, 2.0, 2.5, 3.7):
        np.testing.assert_array_equal(floats.power(y, p), [math.pow(t, p) for t in y])


@pytest.mark.parametrize("dim", [2, 3])
def test_dot_and_norm_sum_in_coordinate_order(dim: int) -> None:
    rng = np.random.default_rng(dim)
    x = rng.normal(size=(3000, dim)) * rng.uniform(1e-3, 1e3, (3000, 1))
    y = rng.normal(size=(3000, dim))
    for a, b in zip(x, y, strict=True):
        acc = a[0] * b[0]
        for d in range(1, dim):
            acc = acc + a[d] * b[d]
        assert floats.dot(a, b) == acc
    # the norm is numpy's row norm (which the kernels' row norm equals: test_step_fast_paths)
    np.testing.assert_array_equal([floats.norm(a) for a in x], np.linalg.norm(x, axis=1))
