"""The multi_target anchors' ball test, compiled (:func:`any_row_beyond`) and numpy.

A sub-step is rejected when an anchored robot would be ``Rz`` or farther from its
target (``||q_i - z_i|| < Rz``, the continuous-connectivity paper's exploration task):
the compiled test must decide exactly as the numpy reference, including robots at
(or one rounding step either side of) ``Rz``, where a ``>`` for ``>=`` or a different
summation order of the squares would flip the decision.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("numba")

from tether import jit  # noqa: E402
from tether.continuous.exploration.step_kernels import any_row_beyond  # noqa: E402
from tether.continuous.exploration.strategy import _anchor_leaves  # noqa: E402


def numpy_test(q: np.ndarray, rows: np.ndarray, targets: np.ndarray, r: float) -> bool:
    return bool(np.any(np.linalg.norm(q[rows] - targets, axis=1) >= r))


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("seed", range(8))
def test_compiled_test_decides_as_numpy_near_and_at_the_radius(dim: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    n, r = 35, 1.8
    q = rng.uniform(-50, 50, (n, dim))
    decided = {True: 0, False: 0}
    for _ in range(300):
        k = int(rng.integers(0, 8))
        rows = rng.choice(n, k, replace=False).astype(np.int64)
        u = rng.normal(size=(k, dim))
        u /= np.linalg.norm(u, axis=1)[:, None]
        dist = r * (1.0 + rng.choice([-1e-15, -(2**-52), 0.0, 2**-52, 1e-15, -0.3, 0.3], k))
        targets = q[rows] + dist[:, None] * u
        rk = r
        if k and rng.random() < 0.3:  # the radius exactly one robot's numpy (row) distance
            rk = float(np.linalg.norm((q[rows[0]] - targets[0])[None], axis=1)[0])
            assert numpy_test(q, rows, targets, rk)
        want = numpy_test(q, rows, targets, rk)
        assert any_row_beyond(q, rows, targets, rk) == want
        with jit.using(True):
            assert _anchor_leaves(q, rows, targets, rk) == want
        with jit.using(False):
            assert _anchor_leaves(q, rows, targets, rk) == want
        decided[want] += 1
        # oracle (away from the radius, where rounding cannot decide): exact distances
        gaps = [math.dist(q[i], z) - rk for i, z in zip(rows, targets, strict=True)]
        if all(abs(g) > 1e-9 for g in gaps):
            assert want == any(g > 0 for g in gaps)
    assert min(decided.values()) > 20  # both answers were exercised


def test_no_anchors_never_leave() -> None:
    q = np.zeros((3, 3))
    rows = np.zeros(0, np.int64)
    assert not any_row_beyond(q, rows, np.zeros((0, 3)), 1.0)
    # a zero radius: every anchor is at or beyond it
    assert any_row_beyond(q, np.array([1], np.int64), np.zeros((1, 3)), 0.0)
