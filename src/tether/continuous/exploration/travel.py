"""Algorithm 2's forces and gains: eqs. (3), (5)-(9), (11), (12), (14), (15).

Continuous-connectivity paper (Nestmeyer et al.), Secs. 3.6-3.7. Every function is
vectorised over robots and uses only robot ``i``'s own state, its own path and
what it received (``lambda_hat``), so the traveling force is decentralized.
"""

from __future__ import annotations

import numpy as np

from tether import floats
from tether.continuous.exploration.tracking import PathState


def travel_force(
    q: np.ndarray,
    v: np.ndarray,
    path: PathState,
    *,
    kp: float,
    kv: float,
    mass_kg: float = 1.0,
    damping_ns_per_m: float = 0.0,
    max_force_n: float = np.inf,
) -> np.ndarray:
    """``f_travel`` of eq. (3): feed-forward, velocity and position feedback, ``(r, dim)``.

    ``f = M a_gamma + B v_gamma + k_v (v_gamma - qdot) + k_p (q_gamma - q)``: with
    ``M = I`` and ``B = 0`` this is eq. (3) as printed. The robot model eq. (1)
    has mass ``M`` and damping ``B``; without ``B v_gamma`` a robot cruising on a
    straight path would settle at ``k_v / (k_v + B) v_cruise`` and its traveling
    efficiency (eq. (12)) could never reach 1, so the feed-forward carries it.
    The norm is saturated at ``max_force_n`` (Problem 1 asks for a bounded force).
    """
    f = (
        mass_kg * path.acceleration_mps2
        + damping_ns_per_m * path.velocity_mps
        + kv * (path.velocity_mps - v)
        + kp * (path.point_m - q)
    )
    return saturate(f, max_force_n)


def saturate(f: np.ndarray, max_norm: float) -> np.ndarray:
    """Rows of ``f`` scaled down to norm ``max_norm`` where longer (direction kept)."""
    if not np.isfinite(max_norm):
        return f
    norm = np.linalg.norm(f, axis=1, keepdims=True)
    return f * np.minimum(1.0, max_norm / np.maximum(norm, 1e-300))


def anchor_potential(distance_m: np.ndarray, rz_m: float, kz: float) -> np.ndarray:
    """``V_anchor(l) = -k_z (2 Rz / pi) ln cos(l pi / (2 Rz))`` (eq. (6)); ``inf`` from ``Rz``."""
    d = np.asarray(distance_m, dtype=float)
    with np.errstate(divide="ignore"):
        c = floats.cos(np.minimum(d, rz_m) * np.pi / (2 * rz_m))
        v = -kz * (2 * rz_m / np.pi) * floats.log(c)
    return np.where(d >= rz_m, np.inf, v)


def anchor_force(
    q: np.ndarray, z: np.ndarray, rz_m: float, kz: float, max_force_n: float = np.inf
) -> np.ndarray:
    """``f_anchor = -k_z tan(l pi / (2 Rz)) (q - z) / l`` (eqs. (5), (7)), ``l = |q - z|``,
    its norm saturated at ``max_force_n``.

    The gradient of :func:`anchor_potential` while that is below the bound: 0 on the
    target, unbounded at the sphere of radius ``Rz`` as printed. Fact 1 of the paper needs
    every ``f_i`` bounded, so the force is saturated like the traveling force; from ``Rz``
    on it is the bound itself, pointing at the target (the ball is then a soft constraint;
    a run counts the anchors that leave it). With ``max_force_n = inf`` (the paper's law)
    rows with ``l >= Rz`` get ``nan`` (the force is undefined there).
    """
    diff = q - z
    dist = np.linalg.norm(diff, axis=1)
    inside = dist < rz_m
    mag = np.where(inside, kz * floats.tan(np.minimum(dist, rz_m) * np.pi / (2 * rz_m)), np.nan)
    if np.isfinite(max_force_n):
        mag = np.where(inside, np.minimum(mag, max_force_n), max_force_n)
    unit = diff / np.maximum(dist, 1e-300)[:, None]
    return -mag[:, None] * unit


def alignment(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``Theta(x, y) = (1 + x.y / (|x| |y|)) / 2``, 1 if either is zero (eq. (8)), ``(r,)``."""
    nx = np.linalg.norm(x, axis=1)
    ny = np.linalg.norm(y, axis=1)
    ok = (nx > 0) & (ny > 0)
    cos = np.einsum("kd,kd->k", x, y) / np.where(ok, nx * ny, 1.0)
    return np.where(ok, 0.5 * (1.0 + np.clip(cos, -1.0, 1.0)), 1.0)


def efficiency(x: np.ndarray, xc: float, xm: float) -> np.ndarray:
    """``Lambda(x, x_c, x_M)`` of eq. (9): 1 up to ``x_c``, a cosine step to 0 at ``x_M``."""
    if not 0 <= xc < xm:
        raise ValueError(f"need 0 <= x_c < x_M (got {xc}, {xm})")
    x = np.asarray(x, dtype=float)
    mid = 0.5 + 0.5 * floats.cos((np.clip(x, xc, xm) - xc) / (xm - xc) * np.pi)
    return np.where(x <= xc, 1.0, np.where(x >= xm, 0.0, mid))


def tracking_error(v: np.ndarray, path: PathState, q: np.ndarray, alpha: float) -> np.ndarray:
    """``e_i = (1 - alpha) |v_gamma - v_i| + alpha |q_gamma - q_i|`` (eq. (11)), ``(r,)``."""
    return (1 - alpha) * np.linalg.norm(path.velocity_mps - v, axis=1) + alpha * np.linalg.norm(
        path.point_m - q, axis=1
    )


def rho(theta: np.ndarray, lambda_hat: np.ndarray, sigma: float) -> np.ndarray:
    """``rho(x, y, sigma) = (1 - x) y^sigma + x (1 - (1 - y)^sigma)`` (eqs. (14), (15)).

    ``x = Theta_i`` (force alignment), ``y`` = the estimate of the prime
    traveler's efficiency, ``sigma >= 1``.
    """
    if not sigma >= 1:
        raise ValueError(f"sigma must be >= 1 (got {sigma})")
    x = np.clip(np.asarray(theta, dtype=float), 0.0, 1.0)
    y = np.clip(np.asarray(lambda_hat, dtype=float), 0.0, 1.0)
    return (1 - x) * floats.power(y, sigma) + x * (1 - floats.power(1 - y, sigma))
