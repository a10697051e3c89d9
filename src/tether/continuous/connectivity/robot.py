"""The robot of eq. (1): a point mass with damping, a declared speed bound and a rigid box.

Continuous-connectivity paper, eq. (1)::

    M_i dv_i/dt = f_B_i + f_lambda_i + f_i,   dq_i/dt = v_i

with scalar ``M_i = m I``. The paper leaves the mass and the damping ``f_B_i = -B_i v_i``
open ("friction phenomena ... and/or a stabilizing control action") and assumes a platform
that tracks any smooth enough trajectory; its robots are quadrotors. A point mass without
any bound is not such a platform, so the model here declares one:

* **Damping** ``B(s) = b + beta / (v_max - s)`` at speed ``s = |v_i|``: the linear drag
  ``b`` of the paper's eq. (1) plus a *speed-limiting* term (``beta``, newtons) that is
  small at cruise and grows without bound as ``s`` nears the platform's top speed
  ``v_max``. It is a positive damping, so eq. (1) stays passive, and it keeps every
  robot below ``v_max`` whatever force acts (the speed bound of a real platform: its
  drag and thrust, or the speed limit of its position controller). The energy it takes
  is reported (``speed_limit_work_j``), so a run in which it mattered says so.
  ``v_max = inf`` gives the paper's linear damping.
* **Bounded external forces.** Fact 1 of the paper needs ``f_i`` bounded: the traveling,
  anchor and helper forces are saturated where they are made (``max_travel_force_n``);
  only the connectivity force ``f_lambda`` is unbounded, as the paper's barrier requires.
* **The world's box** is rigid (:func:`stay_inside`): floor, ceiling and outer walls stop
  a robot (an inelastic contact, counted as ``box_contacts``).

One step of length ``h`` is semi-implicit (symplectic) Euler with the damping taken
implicitly, :func:`damped_step`::

    m v+ + h B(|v+|) v+ = m v + h f,     q+ = q + h v+.

``v+`` is parallel to ``p = m v + h f``; its speed ``s`` solves the scalar equation
``(m + h b) s + h beta s / (v_max - s) = |p|``, a quadratic whose smaller root lies in
``[0, v_max)``. The step is unconditionally stable for the damping (any ``h``), exact in
its energy balance ``m v+ . (v+ - v) = h v+ . (f - B v+)``, and never exceeds ``v_max``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class RobotModel:
    """Mass, damping and speed bound of every robot (see the module docstring).

    Attributes
    ----------
    mass_kg
        ``m`` of ``M_i = m I``.
    damping_ns_per_m
        ``b``: the linear damping of eq. (1).
    max_speed_mps
        ``v_max``: the platform's top speed (``inf``: no bound, the paper's model).
    speed_damping_n
        ``beta``: the speed-limiting damping force is ``beta s / (v_max - s)``; 0 makes
        the bound a hard clip of the speed.
    """

    mass_kg: float = 1.0
    damping_ns_per_m: float = 2.0
    max_speed_mps: float = float("inf")
    speed_damping_n: float = 0.25

    def __post_init__(self) -> None:
        if not (self.mass_kg > 0 and self.damping_ns_per_m >= 0):
            raise ValueError("need mass > 0 and damping >= 0")
        if not (self.max_speed_mps > 0 and self.speed_damping_n >= 0):
            raise ValueError("need max_speed_mps > 0 and speed_damping_n >= 0")

    def damping(self, speed_mps: np.ndarray) -> np.ndarray:
        """``B(s)``, the damping coefficient at speed ``s`` (N s/m), ``inf`` from ``v_max``."""
        s = np.asarray(speed_mps, dtype=float)
        if not np.isfinite(self.max_speed_mps):
            return np.full(s.shape, self.damping_ns_per_m)
        gap = self.max_speed_mps - s
        with np.errstate(divide="ignore"):
            extra = np.where(gap > 0, self.speed_damping_n / np.maximum(gap, 1e-300), np.inf)
        return self.damping_ns_per_m + extra


def _speeds(
    v: np.ndarray, force: np.ndarray, h: float, robot: RobotModel
) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """``p = m v + h f``, ``|p|``, the new speeds ``s`` and ``a = m + h b`` of one step."""
    m, b = robot.mass_kg, robot.damping_ns_per_m
    p = m * v + h * force
    a = m + h * b
    pn = np.sqrt((p * p).sum(axis=1))
    vmax = robot.max_speed_mps
    if not np.isfinite(vmax):
        return p, pn, pn / a, a
    lin = a * vmax + h * robot.speed_damping_n + pn
    c = pn * vmax
    disc = lin * lin - 4.0 * a * c
    s = 2.0 * c / (lin + np.sqrt(np.maximum(disc, 0.0)))  # the smaller root, in [0, v_max)
    s = np.minimum(s, vmax)  # a few ulps above it by rounding
    return p, pn, s, a


def damped_step(
    q: np.ndarray, v: np.ndarray, force: np.ndarray, h: float, robot: RobotModel
) -> tuple[np.ndarray, np.ndarray]:
    """One step of eq. (1) for ``(n, dim)`` arrays (see the module docstring)."""
    p, pn, s, a = _speeds(v, force, h, robot)
    if not np.isfinite(robot.max_speed_mps):
        v_new = p / a
        return q + h * v_new, v_new
    scale = np.where(pn > 0, s / np.where(pn > 0, pn, 1.0), 0.0)
    v_new = p * scale[:, None]
    return q + h * v_new, v_new


def dissipation(
    v: np.ndarray, force: np.ndarray, h: float, robot: RobotModel
) -> tuple[float, float]:
    """The energy the damping takes in the step :func:`damped_step` makes, ``h B(s) s^2``
    summed over robots, and its speed-limiting part.

    The speed-limiting part is computed as ``s (|p| - (m + h b) s)``, which equals
    ``h beta s^2 / (v_max - s)`` by the step's equation without dividing by ``v_max - s``
    (which loses every digit when ``s`` is within rounding of ``v_max``).
    """
    _, pn, s, a = _speeds(v, force, h, robot)
    lin = h * robot.damping_ns_per_m * (s * s)
    limit = s * (pn - a * s) if np.isfinite(robot.max_speed_mps) else np.zeros_like(s)
    lin_sum = float(np.cumsum(lin)[-1]) if lin.size else 0.0  # one term after the other,
    limited = float(np.cumsum(limit)[-1]) if limit.size else 0.0  # as the kernel adds
    return lin_sum + limited, limited


def stay_inside(
    q_old: np.ndarray, q_new: np.ndarray, v_new: np.ndarray, box: np.ndarray, margin_m: float
) -> tuple[np.ndarray, np.ndarray]:
    """The world's box is rigid: floor, ceiling and outer walls stop a robot.

    Each coordinate is clipped to ``[box[0] + margin_m, box[1] - margin_m]`` and the
    velocity component that hit the wall is zeroed (an inelastic contact). A robot
    that starts outside that range is never pushed in, it only cannot move further out.
    Since the box is convex, links between robots inside it stay inside it too.
    """
    lo = np.minimum(box[0] + margin_m, q_old)
    hi = np.maximum(box[1] - margin_m, q_old)
    q = np.clip(q_new, lo, hi)
    return q, np.where(q != q_new, 0.0, v_new)
