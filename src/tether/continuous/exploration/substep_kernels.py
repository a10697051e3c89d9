"""Compiled total force of a ``multi_target`` sub-step (numba, lazy).

:func:`total_force_kernel` is one ``multi_target`` sub-step's total force and step: the
reference is a chain of calls
(:func:`~tether.continuous.connectivity.gradient.connectivity_force`, then
:func:`tether.continuous.exploration.motion.traveling_forces`, a sum, then the
displacement rule) whose Python glue cost more than the arithmetic for 35 robots; it
calls the same kernels in the same order from compiled code, so the forces and the step
are the same bits (``tests/test_kernels.py``, ``tests/test_fused_substep.py``). Its
caller: :func:`tether.continuous.exploration.substep.fused_total_force`.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from tether.continuous.connectivity.dynamics_kernels import displacement_kernel
from tether.continuous.connectivity.force_kernels import (
    edge_energy_kernel,
    force_kernel,
    gradient_kernel,
)
from tether.continuous.exploration.tracking_kernels import traveling_kernel


@njit(cache=True)
def total_force_kernel(  # noqa: ANN201, PLR0913
    q, v, graph, nu, lam, potential, travel, trav, secondary, lambda_hat, held, targets, path,
    v_cruise, tie, order, mass, delta,
):  # noqa: ANN001  # fmt: skip
    """``(f_lambda + f_i, h, f_lambda, f_i)`` of one sub-step: the total force ``(n, dim)``,
    the displacement step and the two forces it sums.

    ``graph``: ``(pairs, pair_factor, collision, dP_di, dP_dj, coll_pairs, coll_unit,
    coll_logd)`` of a :class:`~tether.continuous.connectivity.weights.WeightedGraph`;
    ``nu``, ``lam`` its Fiedler vector and lambda2; ``potential``: ``(lambda2_min,
    lambda2_null, gain)``; ``travel``: ``(kp, kv, mass, damping, max_force, sigma, rz, kz,
    anchor_max)`` and the other arguments as
    :func:`~tether.continuous.exploration.tracking_kernels.traveling_kernel` takes them;
    ``mass``, ``delta``: the displacement rule's (``inf`` step if nothing moves).
    """
    n = q.shape[0]
    pairs, pair_factor, collision, dP_di, dP_dj, coll_pairs, coll_unit, coll_logd = graph
    energy = edge_energy_kernel(n, pairs, pair_factor, collision, nu)
    grad = gradient_kernel(n, pairs, dP_di, dP_dj, coll_pairs, coll_unit, coll_logd, nu,
                           collision, energy)  # fmt: skip
    f_lambda = force_kernel(grad, np.full(n, lam), potential[0], potential[1], potential[2])
    kp, kv, m_t, b_t, max_force, sigma, rz, kz, anchor_max = travel
    f_ext = traveling_kernel(
        q, v, f_lambda, trav, secondary, lambda_hat, held, targets, path, v_cruise, tie, order,
        kp, kv, m_t, b_t, max_force, sigma, rz, kz, anchor_max,
    )  # fmt: skip
    total = f_lambda + f_ext
    return total, displacement_kernel(v, total, mass, delta), f_lambda, f_ext


def warm_up() -> None:
    """Compile (or load) :func:`total_force_kernel` on the connectivity warm-up's team
    (:func:`tether.continuous.connectivity.kernels.tiny_team`), without paths."""
    from tether.continuous.connectivity.kernels import tiny_team

    q, pairs, _, graph, nu = tiny_team()
    pf, dP_di, dP_dj, _, coll, cp, cu, cl = graph
    n = len(q)
    i0, f1, f2 = np.zeros(1, np.int64), np.zeros(0), np.zeros((0, 3))
    no_paths = (i0, f2, f2, f1, f1, f1, f2, f2, f2, f2, f1, f1, f1, i0[:0])
    arrays = (pairs, pf, coll, dP_di, dP_dj, cp, cu, cl)
    travel = (4.0, 4.0, 1.0, 2.0, 10.0, 3.0, 1.8, 1.0, np.inf)
    held = np.arange(1, dtype=np.int64)
    total_force_kernel(q, q, arrays, nu, 0.1, (0.0, 0.5, 1.0), travel, i0[:0],
                       np.zeros(0, np.bool_), np.zeros(n), held, q[:1].copy(), no_paths, 3.0,
                       1e-6, 1, 1.0, 0.1)  # fmt: skip
