"""``Polyline.at``/``project`` on Python floats give numpy's results exactly.

The leader's carrot is computed every ``silent`` step; the scalar clips and norms
replaced ``np.clip``/``np.linalg.norm`` calls. Here the previous numpy formulas are
the reference, on random polylines and points, bit for bit, with their dot products and
norms summed in coordinate order (``np.add.reduce`` of a few elements, the row norm):
numpy's ``@`` of two vectors is a BLAS call, whose summation depends on the CPU.
"""

from __future__ import annotations

import numpy as np
import pytest

from tether.paths.trajectory import Polyline


def _at_numpy(p: Polyline, s_m: float) -> np.ndarray:
    s = float(np.clip(s_m, 0.0, p.length_m))
    if len(p.waypoints) == 1 or p.length_m == 0.0:
        return p.waypoints[0].copy()
    k = int(np.clip(np.searchsorted(p._cum, s, side="right") - 1, 0, len(p._seg_len) - 1))
    frac = (s - p._cum[k]) / max(p._seg_len[k], 1e-12)
    return p.waypoints[k] + frac * (p.waypoints[k + 1] - p.waypoints[k])


def _project_numpy(p: Polyline, point: np.ndarray, s_min: float, window_m: float) -> float:
    best_s, best_d = s_min, np.inf
    for k, (a, b) in enumerate(zip(p.waypoints[:-1], p.waypoints[1:], strict=True)):
        s0, s1 = p._cum[k], p._cum[k + 1]
        if s1 < s_min or s0 > s_min + window_m:
            continue
        ab = b - a
        denom = float(np.add.reduce(ab * ab))
        t = 0.0 if denom == 0 else float(np.clip(np.add.reduce((point - a) * ab) / denom, 0, 1))
        s = float(np.clip(s0 + t * (s1 - s0), s_min, s_min + window_m))
        d = float(np.linalg.norm((_at_numpy(p, s) - point)[None], axis=1)[0])
        if d < best_d:
            best_s, best_d = s, d
    return best_s


@pytest.mark.parametrize("seed", range(6))
@pytest.mark.parametrize("dim", [2, 3])
def test_scalar_path_arithmetic_is_numpys(seed: int, dim: int) -> None:
    rng = np.random.default_rng(seed)
    pts = rng.uniform(-50.0, 50.0, (int(rng.integers(1, 7)), dim))
    if len(pts) > 2:
        pts[2] = pts[1]  # a zero-length segment
    p = Polyline(pts)
    for _ in range(50):
        s = float(rng.uniform(-10.0, p.length_m + 10.0))
        np.testing.assert_array_equal(p.at(s), _at_numpy(p, s))
        point = rng.uniform(-60.0, 60.0, dim)
        s_min, window = float(rng.uniform(0.0, p.length_m + 1.0)), float(rng.choice([5.0, np.inf]))
        assert p.project(point, s_min, window) == _project_numpy(p, point, s_min, window)
