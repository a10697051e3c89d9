"""Compiled kernels of a sub-step's connectivity force (numba, lazy).

The fast paths of :func:`tether.continuous.connectivity.gradient.edge_energy`,
:func:`~tether.continuous.connectivity.gradient.lambda2_gradient` and
:func:`~tether.continuous.connectivity.gradient.connectivity_force` (eqs. (17)-(18)),
each in its reference's arithmetic and order (same bits; ``tests/test_kernels.py``).
"""

from __future__ import annotations

import numpy as np
from numba import njit


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
