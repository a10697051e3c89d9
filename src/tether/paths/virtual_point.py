"""The virtual point travelling along a path at cruise speed (paper, Sec. 3.6, eq. 3).

The traveling force of the continuous-connectivity paper,

``f_travel = a_gamma(v_cruise, q_gamma) + k_v (v_gamma(v_cruise, q_gamma) - qdot)``
``+ k_p (q_gamma - q)``

uses "the velocity vector of a virtual point traveling along gamma_i and passing at
q_gamma with tangential speed v_cruise" and "the acceleration vector of the same
point". For a point at arc length ``s`` moving with speed ``v(s)``:

``velocity = v T(s)``, ``acceleration = v^2 kappa(s) N(s) + v dv/ds T(s)``,

with ``T = dp/ds`` and ``kappa N = d2p/ds2`` from the spline
(:meth:`tether.paths.bspline.SplinePath.derivatives`). At constant cruise speed the
tangential term vanishes and the acceleration is the centripetal ``v^2 kappa N``.

The virtual point stops at the end of the path (the target ``z_i``): by default
abruptly (velocity and acceleration 0 from ``s = length`` on; the paper's robot turns
``anchor`` within ``Rz`` of the target before that), or, given ``stop_decel_mps2``,
with the speed profile ``v(s) = min(v_cruise, sqrt(2 a (L - s)))`` (constant
deceleration ``a`` onto the end; not in the paper).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from tether.paths.bspline import SplinePath

__all__ = ["VirtualPoint", "VirtualState", "virtual_state"]


class VirtualState(NamedTuple):
    """Where the virtual point is and how it moves."""

    s_m: float
    position_m: np.ndarray
    velocity_mps: np.ndarray
    acceleration_mps2: np.ndarray


def _speed(path: SplinePath, s_m: float, v_cruise_mps: float, decel: float | None):
    """Speed ``v(s)`` and ``dv/ds`` of the profile."""
    remaining = path.length_m - s_m
    if remaining <= 0.0:
        return 0.0, 0.0
    if decel is None:
        return v_cruise_mps, 0.0
    brake = math.sqrt(2.0 * decel * remaining)
    if brake >= v_cruise_mps:
        return v_cruise_mps, 0.0
    return brake, -decel / brake  # d/ds sqrt(2 a (L - s)) = -a / v


def virtual_state(
    path: SplinePath,
    s_m: float,
    v_cruise_mps: float,
    *,
    stop_decel_mps2: float | None = None,
) -> VirtualState:
    """State of the virtual point passing arc length ``s_m`` (eq. 3's ``v_gamma``, ``a_gamma``).

    Parameters
    ----------
    path
        The path ``gamma_i``.
    s_m
        Arc length where the point is, e.g. ``closest_point(path, q).s_m``.
    v_cruise_mps
        The paper's ``v_cruise`` (Table 2: 3 m/s outdoor, 1 m/s office).
    stop_decel_mps2
        ``None``: cruise to the end, then stop. A value: brake at this constant
        deceleration so as to stop at the end.

    Returns
    -------
    VirtualState
        ``velocity = v T``, ``acceleration = v^2 d2p/ds2 + v (dv/ds) T``; both zero at
        and beyond the end.
    """
    if v_cruise_mps < 0:
        raise ValueError("v_cruise_mps must be >= 0")
    if stop_decel_mps2 is not None and not stop_decel_mps2 > 0:
        raise ValueError("stop_decel_mps2 must be > 0")
    s = float(np.clip(s_m, 0.0, path.length_m))
    point, tangent, curv = path.derivatives(s)
    v, dv_ds = _speed(path, s, v_cruise_mps, stop_decel_mps2)
    return VirtualState(s, point, v * tangent, v * v * curv + v * dv_ds * tangent)


@dataclass
class VirtualPoint:
    """The virtual point as a function of time: starts at ``s0_m`` at ``t = 0``.

    Parameters
    ----------
    path
        The path.
    v_cruise_mps
        Cruise speed.
    s0_m
        Arc length at ``t = 0``.
    stop_decel_mps2
        See :func:`virtual_state`.
    """

    path: SplinePath
    v_cruise_mps: float
    s0_m: float = 0.0
    stop_decel_mps2: float | None = None

    def s_at(self, t_s: float) -> float:
        """Arc length reached at time ``t_s`` (clamped to the end)."""
        length = self.path.length_m
        s0 = float(np.clip(self.s0_m, 0.0, length))
        v, a = self.v_cruise_mps, self.stop_decel_mps2
        t = max(float(t_s), 0.0)
        if a is None or v == 0.0:
            return min(s0 + v * t, length)
        s_brake = length - v * v / (2.0 * a)  # where braking from v_cruise starts
        if s0 < s_brake:
            t_cruise = (s_brake - s0) / v
            if t <= t_cruise:
                return s0 + v * t
            s0, t, v0 = s_brake, t - t_cruise, v
        else:
            v0 = math.sqrt(2.0 * a * (length - s0))
        t_stop = v0 / a
        if t >= t_stop:
            return length  # exactly: stopped
        return min(s0 + v0 * t - 0.5 * a * t * t, length)

    def at(self, t_s: float) -> VirtualState:
        """State at time ``t_s``."""
        return virtual_state(
            self.path,
            self.s_at(t_s),
            self.v_cruise_mps,
            stop_decel_mps2=self.stop_decel_mps2,
        )
