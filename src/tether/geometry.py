"""Small vectorised geometry helpers shared by sensing, strategies and worlds."""

from __future__ import annotations

import numpy as np


def point_segment_distance(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Distance from points ``p[k]`` to segments ``a[k] -> b[k]`` (all ``(k, dim)``)."""
    ab = b - a
    denom = np.einsum("kd,kd->k", ab, ab)
    t = np.einsum("kd,kd->k", p - a, ab) / np.where(denom > 0, denom, 1.0)
    t = np.clip(t, 0.0, 1.0)
    closest = a + t[:, None] * ab
    return np.linalg.norm(p - closest, axis=1)


def unit(v: np.ndarray, eps: float = 1e-12) -> np.ndarray:
    """Row-wise unit vectors; zero rows stay zero."""
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    return np.where(norm > eps, v / np.maximum(norm, eps), 0.0)


def random_perpendicular(v: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """A random unit vector perpendicular to each row of ``v`` (2-D or 3-D)."""
    v = unit(v)
    if v.shape[1] == 2:
        perp = np.stack([-v[:, 1], v[:, 0]], axis=1)
        sign = rng.choice([-1.0, 1.0], size=len(v))
        return perp * sign[:, None]
    r = rng.normal(size=v.shape)
    r -= np.einsum("kd,kd->k", r, v)[:, None] * v
    bad = np.linalg.norm(r, axis=1) < 1e-9
    if bad.any():  # vanishingly rare: r parallel to v; use a fixed axis instead
        r[bad] = np.cross(v[bad], np.array([1.0, 0.0, 0.0]))
    return unit(r)


def angle_between(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle in radians between rows of ``a`` and ``b`` (0 for zero vectors)."""
    cos = np.einsum("kd,kd->k", unit(a), unit(b))
    return np.arccos(np.clip(cos, -1.0, 1.0))
