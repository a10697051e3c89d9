"""Compiled kernels of the integrator (numba, lazy): one step of eq. (1) and its bookkeeping.

Each kernel does its reference's arithmetic in its reference's order, so both give the same
bits (``tests/test_dynamics.py``):

* :func:`step_kernel`: :func:`tether.continuous.connectivity.robot.damped_step` and
  :func:`~tether.continuous.connectivity.robot.dissipation`, then
  :func:`~tether.continuous.connectivity.robot.stay_inside` if ``box`` has two rows;
* :func:`displacement_kernel`: :func:`tether.continuous.connectivity.dynamics.displacement_step`;
* :func:`terms_kernel`: :func:`tether.continuous.connectivity.dynamics.substep_terms`.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True)
def step_kernel(q, v, force, h, mass, damping, vmax, beta, box, margin):  # noqa: ANN001, ANN201
    """``(q+, v+, contacts, dissipated, speed_limit)``:
    :func:`~tether.continuous.connectivity.robot.damped_step` (``vmax = inf``: linear
    damping) and its :func:`~tether.continuous.connectivity.robot.dissipation`, then the box
    (``contacts``: velocity components stopped by a wall)."""
    n, dim = q.shape
    q_new = np.empty((n, dim))
    v_new = np.empty((n, dim))
    a = mass + h * damping
    limited = vmax < np.inf
    contacts = 0
    lin_sum, limit_sum = 0.0, 0.0
    for r in range(n):
        scale = 0.0
        pn = 0.0
        for c in range(dim):
            pc = mass * v[r, c] + h * force[r, c]
            pn += pc * pc
        pn = math.sqrt(pn)
        if limited:
            lin = a * vmax + h * beta + pn
            cc = pn * vmax
            disc = lin * lin - 4.0 * a * cc
            s = min(2.0 * cc / (lin + math.sqrt(max(disc, 0.0))), vmax)
            scale = s / pn if pn > 0 else 0.0
            lin_sum += h * damping * (s * s)
            limit_sum += s * (pn - a * s)
        else:
            s = pn / a
            lin_sum += h * damping * (s * s)
        for c in range(dim):
            pc = mass * v[r, c] + h * force[r, c]
            vn = pc * scale if limited else pc / a
            qn = q[r, c] + h * vn
            if len(box) == 2:
                lo = min(box[0, c] + margin, q[r, c])
                hi = max(box[1, c] - margin, q[r, c])
                clipped = min(max(qn, lo), hi)
                if clipped != qn:
                    vn = 0.0
                    contacts += 1
                qn = clipped
            q_new[r, c] = qn
            v_new[r, c] = vn
    return q_new, v_new, contacts, lin_sum + limit_sum, limit_sum


@njit(cache=True)
def displacement_kernel(v, force, mass, delta):  # noqa: ANN001, ANN201
    """:func:`~tether.continuous.connectivity.dynamics.displacement_step` (``inf`` if
    nothing moves)."""
    n, dim = v.shape
    vmax, fmax = 0.0, 0.0
    for r in range(n):
        sv, sf = 0.0, 0.0
        for c in range(dim):
            sv += v[r, c] * v[r, c]
            sf += force[r, c] * force[r, c]
        vmax = max(vmax, math.sqrt(sv))
        fmax = max(fmax, math.sqrt(sf))
    disc = vmax * vmax + 4.0 * delta * fmax / mass
    denom = vmax + math.sqrt(disc)
    return np.inf if denom <= 0 else 2.0 * delta / denom


@njit(cache=True)
def terms_kernel(q, v, q1, v1, f, f1, f_c, pairs, h, mass):  # noqa: ANN001, ANN201
    """:func:`~tether.continuous.connectivity.dynamics.substep_terms` as a tuple of six floats."""
    n, dim = q.shape
    dq = np.empty(n)
    df = np.empty(n)
    work, kinetic, speed, accel = 0.0, 0.0, 0.0, 0.0
    for r in range(n):
        sq, sf, s1, sa = 0.0, 0.0, 0.0, 0.0
        for c in range(dim):
            d = q1[r, c] - q[r, c]
            g = f1[r, c] - f[r, c]
            sq += d * d
            sf += g * g
            work += (f[r, c] - f_c[r, c]) * d
            kinetic += 0.5 * mass * (v1[r, c] * v1[r, c] - v[r, c] * v[r, c])
            s1 += v1[r, c] * v1[r, c]
            a = v1[r, c] - v[r, c]
            sa += a * a
        dq[r] = math.sqrt(sq)
        df[r] = math.sqrt(sf)
        speed = max(speed, math.sqrt(s1))
        accel = max(accel, math.sqrt(sa) / h)
    reach = dq.copy()
    for k in range(len(pairs)):
        i, j = pairs[k, 0], pairs[k, 1]
        reach[i] = max(reach[i], dq[j])
        reach[j] = max(reach[j], dq[i])
    omega2, jump = 0.0, 0.0
    for r in range(n):
        jump = max(jump, df[r])
        if reach[r] > 0:
            omega2 = max(omega2, df[r] / (mass * reach[r]))
        elif df[r] > 0:
            omega2 = np.inf
    return omega2, jump, work, kinetic, speed, accel


def warm_up() -> None:
    """Compile (or load) every kernel here on a tiny team."""
    q = np.arange(9.0).reshape(3, 3)
    box = np.array([[-10.0, -10.0, 0.0], [10.0, 10.0, 5.0]])
    pairs = np.array([[0, 1], [1, 2]], dtype=np.int64)
    for corners in (box, np.zeros((0, 3))):
        for vmax in (np.inf, 6.0):
            step_kernel(q, q, q, 0.01, 1.0, 2.0, vmax, 0.25, corners, 0.75)
    displacement_kernel(q, q, 1.0, 0.1)
    terms_kernel(q, q, q, q, q, q, q, pairs, 0.01, 1.0)
