"""Reference trajectories for a leader: polylines at constant speed, or any function of time."""

from __future__ import annotations

import bisect
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from tether import floats


def _clip(x: float, lo: float, hi: float) -> float:
    """``float(np.clip(x, lo, hi))`` for one number, without numpy's call overhead.

    ``np.clip`` is ``minimum(maximum(x, lo), hi)``; so is this (NaN stays NaN).
    """
    x = float(x)
    return x if x != x else min(max(x, lo), hi)


@dataclass
class Polyline:
    """A piecewise-linear path through ``waypoints`` (``(k, dim)``), parametrised by arc length."""

    waypoints: np.ndarray

    def __post_init__(self) -> None:
        try:
            points = np.asarray(self.waypoints, dtype=float)
        except (TypeError, ValueError):
            raise ValueError(
                "waypoints must be a (k, dim) array of numbers (ragged or non-numeric given)"
            ) from None
        points = np.atleast_2d(points)
        if points.ndim != 2 or points.shape[0] < 1 or points.shape[1] < 1:
            raise ValueError(
                f"waypoints must be a (k, dim) array with at least one point (got shape "
                f"{np.shape(self.waypoints)})"
            )
        if not np.isfinite(points).all():
            k = int(np.argmin(np.isfinite(points).all(axis=1)))
            raise ValueError(f"waypoints must be finite (point {k} is {points[k].tolist()})")
        self.waypoints = points
        seg = np.diff(self.waypoints, axis=0)
        self._seg_len = np.linalg.norm(seg, axis=1)
        self._cum = np.concatenate([[0.0], np.cumsum(self._seg_len)])
        # per-segment values the leader's carrot needs every step, computed once (the
        # same expressions as before, so the same bits): b - a, |b - a|^2, arc lengths
        self._seg = seg
        self._denom = [floats.dot(ab, ab) for ab in seg]
        self._cum_list = self._cum.tolist()
        self._seg_len_list = self._seg_len.tolist()
        self._length_m = float(self._cum[-1])
        self._points = self.waypoints.tolist()  # as Python floats: at() adds them one by one
        self._seg_rows = seg.tolist()

    @property
    def length_m(self) -> float:
        return self._length_m

    @property
    def end(self) -> np.ndarray:
        return self.waypoints[-1]

    def at(self, s_m: float) -> np.ndarray:
        """Point at arc length ``s_m`` (clamped to the path)."""
        s = _clip(s_m, 0.0, self._length_m)
        if len(self._points) == 1 or self._length_m == 0.0:
            return self.waypoints[0].copy()
        k = bisect.bisect_right(self._cum_list, s) - 1  # np.searchsorted(side="right")
        k = min(max(k, 0), len(self._seg_len_list) - 1)
        frac = (s - self._cum_list[k]) / max(self._seg_len_list[k], 1e-12)
        # waypoints[k] + frac * seg[k], coordinate by coordinate (the same IEEE operations)
        a, ab = self._points[k], self._seg_rows[k]
        return np.array([a[c] + frac * ab[c] for c in range(len(a))])

    def project(self, point: np.ndarray, s_min: float = 0.0, window_m: float = np.inf) -> float:
        """Arc length of the path point closest to ``point`` in ``[s_min, s_min + window_m]``."""
        best_s, best_d = s_min, np.inf
        cum = self._cum_list
        for k in range(len(self._denom)):
            s0, s1 = cum[k], cum[k + 1]
            if s1 < s_min or s0 > s_min + window_m:
                continue
            a, ab, denom = self.waypoints[k], self._seg[k], self._denom[k]
            # (point - a) . ab summed in coordinate order (numpy's dot is BLAS: by CPU)
            t = 0.0 if denom == 0 else _clip(floats.dot(point - a, ab) / denom, 0.0, 1.0)
            s = _clip(s0 + t * (s1 - s0), s_min, s_min + window_m)
            gap = self.at(s) - point
            d = floats.norm(gap)
            if d < best_d:
                best_s, best_d = s, d
        return best_s

    def segments(self) -> tuple[np.ndarray, np.ndarray]:
        return self.waypoints[:-1], self.waypoints[1:]


TimeFunction = Callable[[float], np.ndarray]
