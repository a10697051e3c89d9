"""The analytic gradient of lambda2 and the connectivity force (eqs. (17)-(18)).

Continuous-connectivity paper (Nestmeyer et al., "Decentralized simultaneous
multi-target exploration using a connected network of multiple robots"),
Sec. 2 and Appendix A, after Robuffo Giordano et al. (2013).

Gradient
--------
Eq. (18) of the paper (Yang et al. 2010) reads
``dlambda2/dq_i = sum_{j in N_i} dW_ij/dq_i (nu_i - nu_j)^2`` with the unit
Fiedler vector ``nu``. It holds when ``W_ij`` depends only on ``q_i, q_j``;
with the collision factor, ``q_i`` also enters every weight ``W_jk`` of a
robot ``j`` within ``R'c`` of ``i``. The exact gradient
``dlambda2/dq_i = sum_{(j,k)} dW_jk/dq_i (nu_j - nu_k)^2`` then is::

    dlambda2/dq_i = sum_{j in N_i} dP_ij/dq_i C_i C_j (nu_i - nu_j)^2       (pair term, eq. 18)
                  + sum_{k: d_ik < R'c} r(d_ik) u_ik (T_i + T_k)              (collision terms)

with ``u_ik = (q_i - q_k) / d_ik``, ``r = G'/G`` (the log-derivative of the
step, finite and computed without dividing by ``G``) and the *local edge
energy* ``T_i = sum_j W_ij (nu_i - nu_j)^2`` that robot ``j`` can compute and
send. ``dP_ij/dq_i`` contains the range term ``A'(d_ij) u_ij B`` and the
obstacle term ``A B'(d_ijo) (1 - s*) (p* - o*) / d_ijo`` (closest point
``p* = q_i + s* (q_j - q_i)`` on the segment, closest obstacle point ``o*``).
The finite-difference tests check this expression; eq. (18) alone does not
pass them when collision factors are active.

Locality
--------
The *neighbourhood* of robot ``i`` is ``N_i = {j != i : d_ij < Rs}``; because
``R'c < Rs`` (checked) it contains the collision neighbours
``{k : d_ik < R'c}``. Robot ``i``'s gradient is a function of ``q_i``, the
positions of ``N_i``, the obstacle points within ``Rs + R'o`` of ``q_i``,
``nu_i`` and the three scalars ``(nu_j, C_j, T_j)`` that each ``j in N_i``
sends (see :func:`messages` and :func:`lambda2_gradient`). ``C_j`` and
``T_j`` depend on ``j``'s own neighbours, so with messages recomputed from
scratch robot ``i``'s force depends on its 2-hop neighbourhood; with the
messages held fixed it depends only on ``N_i``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from tether import jit
from tether.continuous.connectivity.params import ConnectivityParams
from tether.continuous.connectivity.potential import potential_slope
from tether.continuous.connectivity.weights import WeightedGraph


@dataclass
class Messages:
    """What every robot sends its neighbours each step: ``nu_j``, ``C_j``, ``T_j``."""

    nu: np.ndarray
    collision: np.ndarray
    edge_energy: np.ndarray


def edge_energy(graph: WeightedGraph, nu: np.ndarray) -> np.ndarray:
    """``T_i = sum_j W_ij (nu_i - nu_j)^2`` per robot (computable by robot ``i``)."""
    if jit.enabled():
        from tether.continuous.connectivity.force_kernels import edge_energy_kernel

        return edge_energy_kernel(graph.n, graph.pairs, graph.pair_factor, graph.collision,
                                  np.ascontiguousarray(nu, dtype=float))  # fmt: skip
    i, j = graph.pairs[:, 0], graph.pairs[:, 1]
    e = graph.weights * (nu[i] - nu[j]) ** 2
    return np.bincount(i, e, graph.n) + np.bincount(j, e, graph.n)


def messages(graph: WeightedGraph, nu: np.ndarray) -> Messages:
    """The per-robot broadcast values at the current configuration."""
    nu = np.asarray(nu, dtype=float)
    return Messages(nu=nu, collision=graph.collision.copy(), edge_energy=edge_energy(graph, nu))


def lambda2_gradient(graph: WeightedGraph, msg: Messages) -> np.ndarray:
    """``dlambda2/dq_i`` for every robot, ``(n, dim)`` (eq. (18) plus collision terms).

    Robot ``i``'s row uses only its own pairs and collision pairs (all inside
    ``N_i``), its own ``C_i``, ``nu_i``, ``T_i`` and its neighbours' messages.
    With ``msg = messages(graph, nu)`` for the exact unit Fiedler vector it is
    the exact gradient of lambda2 (where lambda2 is simple).
    """
    if jit.enabled() and graph.dP_di.ndim == 2:
        from tether.continuous.connectivity.force_kernels import gradient_kernel

        return gradient_kernel(
            graph.n, graph.pairs, graph.dP_di, graph.dP_dj, graph.coll_pairs, graph.coll_unit,
            graph.coll_logd, np.ascontiguousarray(msg.nu, dtype=float), msg.collision,
            msg.edge_energy,
        )  # fmt: skip
    dim = graph.dP_di.shape[1] if graph.dP_di.ndim == 2 else 0
    grad = np.zeros((graph.n, dim))
    i, j = graph.pairs[:, 0], graph.pairs[:, 1]
    cc = msg.collision[i] * msg.collision[j] * (msg.nu[i] - msg.nu[j]) ** 2
    np.add.at(grad, i, graph.dP_di * cc[:, None])  # eq. (18), pair factor
    np.add.at(grad, j, graph.dP_dj * cc[:, None])
    if len(graph.coll_pairs):
        a, b = graph.coll_pairs[:, 0], graph.coll_pairs[:, 1]
        coef = graph.coll_logd * (msg.edge_energy[a] + msg.edge_energy[b])
        term = coef[:, None] * graph.coll_unit  # d d_ab / d q_a = u_ab
        np.add.at(grad, a, term)
        np.add.at(grad, b, -term)
    return grad


def connectivity_force(
    graph: WeightedGraph, lambda2: float | np.ndarray, msg: Messages, params: ConnectivityParams
) -> np.ndarray:
    """``f_lambda_i = -dV/dlambda2 * dlambda2/dq_i`` (eq. (17)), ``(n, dim)``.

    ``lambda2`` may be a scalar or each robot's own estimate ``(n,)``.
    """
    lam = np.broadcast_to(np.asarray(lambda2, dtype=float), (graph.n,))
    grad = lambda2_gradient(graph, msg)
    if jit.enabled():
        from tether.continuous.connectivity.force_kernels import force_kernel

        return force_kernel(grad, np.ascontiguousarray(lam), params.lambda2_min,
                            params.lambda2_null, params.potential_gain)  # fmt: skip
    return -potential_slope(lam, params)[:, None] * grad


def exact_force(
    graph: WeightedGraph, lambda2: float, nu: np.ndarray, params: ConnectivityParams
) -> np.ndarray:
    """``connectivity_force(graph, lambda2, messages(graph, nu), params)``, ``(n, dim)``.

    The force of the exact eigenpair (every robot's messages from the same ``nu``); with
    the kernels one compiled call, the same bits as the chain; none when the weights'
    kernel call made it already (:func:`tether.continuous.connectivity.weights.compute_weights` with
    ``with_force``: the same kernel on the same arrays).
    """
    done = graph.cached_force(lambda2, nu, params)
    if done is not None:
        return done
    if jit.enabled() and graph.dP_di.ndim == 2:
        from tether.continuous.connectivity.force_kernels import exact_force_kernel

        return exact_force_kernel(
            graph.n, graph.pairs, graph.pair_factor, graph.collision, graph.dP_di, graph.dP_dj,
            graph.coll_pairs, graph.coll_unit, graph.coll_logd,
            np.ascontiguousarray(nu, dtype=float), float(lambda2), params.lambda2_min,
            params.lambda2_null, params.potential_gain,
        )  # fmt: skip
    return connectivity_force(graph, lambda2, messages(graph, nu), params)
