"""Compiled kernels of a sub-step's forces and motion (numba, lazy).

The fast paths of :func:`tether.continuous.connectivity.gradient.edge_energy`,
:func:`~tether.continuous.connectivity.gradient.lambda2_gradient` and
:func:`~tether.continuous.connectivity.gradient.connectivity_force` (eqs. (17)-(18)), each in its
reference's arithmetic and order (same bits; ``tests/test_kernels.py``).

:func:`total_force_kernel` is one ``multi_target`` sub-step's total force and step:
the reference is a chain of calls (``connectivity_force``, then
:func:`tether.continuous.exploration.motion.traveling_forces`, a sum, then the displacement
rule) whose Python glue cost more than the arithmetic for 35 robots; it calls the same
kernels in the same order from compiled code, so the forces and the step are the same
bits.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from tether.continuous.connectivity.dynamics_kernels import displacement_kernel
from tether.continuous.exploration.tracking_kernels import traveling_kernel


@njit(cache=True)
def edge_energy_kernel(n, pairs, pair_factor, collision, nu):  # noqa: ANN001, ANN201
    """``T_i = sum_j W_ij (nu_i - nu_j)^2`` as
    :func:`~tether.continuous.connectivity.gradient.edge_energy`."""
    first = np.zeros(n)
    second = np.zeros(n)
    for k in range(len(pairs)):
        i, j = pairs[k, 0], pairs[k, 1]
        dn = nu[i] - nu[j]
        e = pair_factor[k] * collision[i] * collision[j] * (dn * dn)
        first[i] += e
    for k in range(len(pairs)):
        i, j = pairs[k, 0], pairs[k, 1]
        dn = nu[i] - nu[j]
        e = pair_factor[k] * collision[i] * collision[j] * (dn * dn)
        second[j] += e
    return first + second


@njit(cache=True)
def gradient_kernel(  # noqa: ANN201, PLR0913
    n, pairs, dP_di, dP_dj, coll_pairs, coll_unit, coll_logd, nu, collision, energy
):  # noqa: ANN001
    """``dlambda2/dq`` as :func:`~tether.continuous.connectivity.gradient.lambda2_gradient`,
    ``(n, dim)``."""
    dim = dP_di.shape[1]
    grad = np.zeros((n, dim))
    m = len(pairs)
    cc = np.empty(m)
    for k in range(m):
        i, j = pairs[k, 0], pairs[k, 1]
        dn = nu[i] - nu[j]
        cc[k] = collision[i] * collision[j] * (dn * dn)
    for k in range(m):
        for c in range(dim):
            grad[pairs[k, 0], c] += dP_di[k, c] * cc[k]
    for k in range(m):
        for c in range(dim):
            grad[pairs[k, 1], c] += dP_dj[k, c] * cc[k]
    mc = len(coll_pairs)
    for k in range(mc):
        coef = coll_logd[k] * (energy[coll_pairs[k, 0]] + energy[coll_pairs[k, 1]])
        for c in range(dim):
            grad[coll_pairs[k, 0], c] += coef * coll_unit[k, c]
    for k in range(mc):
        coef = coll_logd[k] * (energy[coll_pairs[k, 0]] + energy[coll_pairs[k, 1]])
        for c in range(dim):
            grad[coll_pairs[k, 1], c] += -(coef * coll_unit[k, c])
    return grad


@njit(cache=True)
def force_kernel(grad, lam, lo, hi, gain):  # noqa: ANN001, ANN201
    """``-dV/dlambda2 * grad`` per robot
    (:func:`~tether.continuous.connectivity.gradient.connectivity_force`).

    ``lam`` is each robot's lambda2 ``(n,)``; the slope is
    :func:`~tether.continuous.connectivity.potential.potential_slope`.
    """
    n, dim = grad.shape
    out = np.empty((n, dim))
    for r in range(n):
        a = max(hi - lam[r], 0.0)
        b = max(lam[r] - lo, 1e-12)
        slope = -gain * a * (a + 2.0 * b) / (b * b)
        for c in range(dim):
            out[r, c] = -slope * grad[r, c]
    return out


@njit(cache=True)
def exact_force_kernel(  # noqa: ANN201, PLR0913
    n, pairs, pair_factor, collision, dP_di, dP_dj, coll_pairs, coll_unit, coll_logd, nu, lam,
    lo, hi, gain,
):  # noqa: ANN001  # fmt: skip
    """``connectivity_force(graph, lam, messages(graph, nu), params)`` in one call: the
    edge energies, the gradient and the force by the three kernels above, in that order."""
    energy = edge_energy_kernel(n, pairs, pair_factor, collision, nu)
    grad = gradient_kernel(n, pairs, dP_di, dP_dj, coll_pairs, coll_unit, coll_logd, nu,
                           collision, energy)  # fmt: skip
    return force_kernel(grad, np.full(n, lam), lo, hi, gain)


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


def warm_up(q: np.ndarray, pairs: np.ndarray, graph: tuple, nu: np.ndarray) -> None:
    """Compile (or load) every kernel here on a tiny team: ``graph`` is
    :func:`~tether.continuous.connectivity.kernels.weights_kernel`'s output for ``q``,
    ``pairs``."""
    pf, dP_di, dP_dj, _, coll, cp, cu, cl = graph
    n = len(q)
    energy = edge_energy_kernel(n, pairs, pf, coll, nu)
    grad = gradient_kernel(n, pairs, dP_di, dP_dj, cp, cu, cl, nu, coll, energy)
    force_kernel(grad, np.full(n, 0.1), 0.0, 0.5, 1.0)
    exact_force_kernel(n, pairs, pf, coll, dP_di, dP_dj, cp, cu, cl, nu, 0.1, 0.0, 0.5, 1.0)
    i0, f1, f2 = np.zeros(1, np.int64), np.zeros(0), np.zeros((0, 3))
    no_paths = (i0, f2, f2, f1, f1, f1, f2, f2, f2, f2, f1, f1, f1, i0[:0])
    arrays = (pairs, pf, coll, dP_di, dP_dj, cp, cu, cl)
    travel = (4.0, 4.0, 1.0, 2.0, 10.0, 3.0, 1.8, 1.0, np.inf)
    held = np.arange(1, dtype=np.int64)
    total_force_kernel(q, q, arrays, nu, 0.1, (0.0, 0.5, 1.0), travel, i0[:0],
                       np.zeros(0, np.bool_), np.zeros(n), held, q[:1].copy(), no_paths, 3.0,
                       1e-6, 1, 1.0, 0.1)  # fmt: skip
