"""The robot model of eq. (1) and an integrator that keeps the invariants.

Continuous-connectivity paper, eq. (1)::

    M_i dv_i/dt = f_B_i + f_lambda_i + f_i,   f_B_i = -B_i v_i,   dq_i/dt = v_i

with scalar ``M_i = m I`` and ``B_i = b I`` (the paper leaves both open; the
defaults ``m = 1 kg``, ``b = 2 N s/m`` give a 1.5 m/s terminal speed per 3 N).

Integrator
----------
Semi-implicit (symplectic) Euler with the damping taken implicitly::

    v+ = (m v + h f(q)) / (m + h b),      q+ = q + h v+.

It is unconditionally stable for the damping term and exact for the energy
balance of the damped oscillator to first order. Its step ``h`` is chosen
inside each control period ``dt`` by two rules:

1. **Displacement rule.** No robot may move more than ``delta = max_step_m``
   in one sub-step (the strategy uses a tenth of the narrowest transition
   band, ``min(Rs - R's, R'o - Ro, R'c - Rc)``):
   a weight then crosses at most a small fraction of its transition band per
   sub-step, so the sampled force sees every band it enters. Since
   ``h |v+| <= h |v| + h^2 |f| / m``, the largest ``h`` that guarantees it is
   ``h = 2 delta / (|v| + sqrt(|v|^2 + 4 delta |f| / m))`` (maxima over robots).
   Near ``lambda2_min`` the force grows like ``dV/dlambda2``, so ``h``
   shrinks like ``|f|^(-1/2)``: the step size follows the potential's growth.
2. **Safeguard (step rejection).** A sub-step is accepted only if lambda2 of
   the new configuration keeps at least ``keep_fraction`` of the current
   margin ``lambda2 - lambda2_min``; otherwise ``h`` is halved and the
   sub-step retried (at most ``max_halvings`` times; if none is admissible
   the team brakes to rest for the rest of the period). The new lambda2 must
   also exceed ``lambda2_min`` by ``lambda2_tolerance`` (1e-9): a computed
   lambda2 at round-off level (about 1e-16 times the Laplacian's norm) does
   not certify connectivity. This is the discrete
   counterpart of the continuous-time guarantee (App. A: under ``f_lambda``
   lambda2 never reaches ``lambda2_min``): lambda2 can approach
   ``lambda2_min`` only geometrically while the barrier force takes over.
   Since ``W_ij = 0`` whenever two robots are within ``Rc``, a link's line
   of sight is within ``Ro`` of an obstacle, or a robot is within ``Ro`` of
   an obstacle with all its links, ``lambda2 > lambda2_min >= 0`` implies
   all three safety invariants.

3. **The world's box.** When the world has bounds (the 3-D scenes: floor,
   ceiling, outer walls), a candidate is clipped to the box shrunk by ``Ro``
   and the velocity into the wall is zeroed (:func:`stay_inside`) before the
   safeguard checks it, so robots neither sink below the floor nor leave the map.

The check uses the exact lambda2 of the candidate configuration, which the
next sub-step's force computation reuses, so a sub-step costs one weight
evaluation and one eigen-decomposition when it is accepted.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import cache
from typing import Any

import numpy as np

from tether import jit


@dataclass(frozen=True)
class IntegratorParams:
    """Mass, damping and the step-size rules (see the module docstring)."""

    mass_kg: float = 1.0
    damping_ns_per_m: float = 2.0
    max_step_m: float = 0.1
    keep_fraction: float = 0.5
    lambda2_tolerance: float = 1e-9
    max_halvings: int = 30
    max_substeps: int = 10_000

    def __post_init__(self) -> None:
        if not (self.mass_kg > 0 and self.damping_ns_per_m >= 0 and self.max_step_m > 0):
            raise ValueError("need mass > 0, damping >= 0 and max_step_m > 0")
        if not 0 <= self.keep_fraction < 1:
            raise ValueError("keep_fraction must be in [0, 1)")


def semi_implicit_euler(
    q: np.ndarray, v: np.ndarray, force: np.ndarray, h: float, mass: float, damping: float
) -> tuple[np.ndarray, np.ndarray]:
    """One step of eq. (1): ``v+ = (m v + h f) / (m + h b)``, ``q+ = q + h v+``.

    For ``(n, dim)`` team arrays with the kernels on (:func:`tether.jit.enabled`), the
    same arithmetic compiled (:func:`tether.continuous.force_kernels.euler_kernel`).
    """
    if q.ndim == 2 and jit.enabled():
        return _euler_kernel()(np.ascontiguousarray(q, dtype=float),
                            np.ascontiguousarray(v, dtype=float),
                            np.ascontiguousarray(force, dtype=float), float(h), float(mass),
                            float(damping), _NO_BOX, 0.0)  # fmt: skip
    v_new = (mass * v + h * force) / (mass + h * damping)
    return q + h * v_new, v_new


_NO_BOX = np.zeros((0, 3))  # euler_kernel's box for none (one row per corner)


@cache
def _euler_kernel() -> Callable:
    """:func:`tether.continuous.force_kernels.euler_kernel`, imported on first use (it loads
    numba; an import statement per call costs microseconds)."""
    from tether.continuous.force_kernels import euler_kernel

    return euler_kernel


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


def displacement_step(v: np.ndarray, force: np.ndarray, mass: float, delta_m: float) -> float:
    """The largest ``h`` with ``h |v_i| + h^2 |f_i| / m <= delta_m`` for every robot."""
    vmax = float(np.max(np.linalg.norm(v, axis=1), initial=0.0))
    fmax = float(np.max(np.linalg.norm(force, axis=1), initial=0.0))
    disc = vmax * vmax + 4.0 * delta_m * fmax / mass
    denom = vmax + np.sqrt(disc)
    return float("inf") if denom <= 0 else 2.0 * delta_m / denom


@dataclass
class IntegrationStats:
    substeps: int = 0
    rejections: int = 0
    min_step_s: float = float("inf")
    stalled: bool = False


# evaluate(q) -> (lambda2 of q for the safeguard, cache); force(cache) -> f_lambda;
# external(q, v, f_lambda) -> f_i, a feedback law evaluated at every sub-step
Evaluate = Callable[[np.ndarray], tuple[float, Any]]
Force = Callable[[Any], np.ndarray]
External = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]
# total_force(q, v, cache) -> (f_lambda + f_i, displacement step): both in one call
TotalForce = Callable[[np.ndarray, np.ndarray, Any], tuple[np.ndarray, float]]


def integrate(
    q: np.ndarray,
    v: np.ndarray,
    dt_s: float,
    evaluate: Evaluate,
    force: Force,
    external: np.ndarray | External,
    params: IntegratorParams,
    lambda2_min: float,
    current: tuple[float, Any] | None = None,
    box: np.ndarray | None = None,
    box_margin_m: float = 0.0,
    total_force: TotalForce | None = None,
) -> tuple[np.ndarray, np.ndarray, tuple[float, Any], IntegrationStats]:
    """Advance eq. (1) by ``dt_s`` with adaptive sub-steps.

    Parameters
    ----------
    q, v
        ``(n, dim)`` positions and velocities.
    dt_s
        Control period to cover.
    evaluate
        ``evaluate(q) -> (lambda2, cache)``: lambda2 of a candidate
        configuration (``inf`` disables the safeguard) and whatever the force
        needs (weights, eigenpair); called for every candidate.
    force
        ``force(cache) -> f_lambda`` ``(n, dim)``; called once per accepted
        sub-step (so a stateful estimator advances once per sub-step).
    external
        The external force ``f_i``: an ``(n, dim)`` array held over the period,
        or a feedback law ``external(q, v, f_lambda) -> (n, dim)`` evaluated at
        the start of every sub-step (a PD law must see the current state).
    current
        ``evaluate(q)`` if already known (reused from the previous period).
    box, box_margin_m
        ``(2, dim)`` lower and upper corners of the world, kept ``box_margin_m``
        away (see :func:`stay_inside`); ``None`` for unbounded space.
    total_force
        ``total_force(q, v, cache) -> (f_lambda + f_i, h)``: the sum of ``force`` and
        ``external`` and the displacement rule's step in one call, with the same values
        (a compiled fast path); ``force`` and ``external`` are then not called.

    Returns
    -------
    q, v, evaluation at the final ``q``, statistics.
    """
    stats = IntegrationStats()
    m, b = params.mass_kg, params.damping_ns_per_m
    ev = current if current is not None else evaluate(q)
    t = 0.0
    kernels = jit.enabled()  # the same arithmetic, compiled (tether.continuous.force_kernels)
    if kernels:
        from tether.continuous.force_kernels import displacement_kernel, euler_kernel

        corners = np.zeros((0, q.shape[1])) if box is None else np.ascontiguousarray(box, float)
    while t < dt_s * (1 - 1e-12) and stats.substeps < params.max_substeps:
        lam = ev[0]
        if total_force is not None:
            total, h_move = total_force(q, v, ev[1])
        else:
            f_lambda = force(ev[1])
            total = f_lambda + (external(q, v, f_lambda) if callable(external) else external)
            step = displacement_kernel if kernels else displacement_step
            h_move = step(v, total, m, params.max_step_m)
        h = min(dt_s - t, h_move)
        floor = lambda2_min + params.keep_fraction * (lam - lambda2_min)
        accepted = False
        for _ in range(params.max_halvings + 1):
            if kernels:
                q_new, v_new = euler_kernel(q, v, total, h, m, b, corners, box_margin_m)
            else:
                q_new, v_new = semi_implicit_euler(q, v, total, h, m, b)
                if box is not None:
                    q_new, v_new = stay_inside(q, q_new, v_new, box, box_margin_m)
            ev_new = evaluate(q_new)
            if ev_new[0] > floor and ev_new[0] > lambda2_min + params.lambda2_tolerance:
                accepted = True
                break
            stats.rejections += 1
            h *= 0.5
        stats.substeps += 1
        if not accepted:  # no admissible step: stop and brake, never cross the invariant
            stats.stalled = True
            v = np.zeros_like(v)
            break
        q, v, ev = q_new, v_new, ev_new
        t += h
        stats.min_step_s = min(stats.min_step_s, h)
    return q, v, ev, stats
