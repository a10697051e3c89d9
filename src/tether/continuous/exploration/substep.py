"""The fused force of a ``multi_target`` sub-step: one compiled call instead of a chain.

:func:`fused_total_force` makes the ``forces`` of
:class:`tether.continuous.connectivity.dynamics.System` for one control period: it computes
``f_lambda`` (eq. (17)) as :meth:`ConnectivityStrategy.connectivity_force
<tether.continuous.connectivity.strategy.ConnectivityStrategy.connectivity_force>` does,
the traveling force of Algorithm 2 as
:func:`tether.continuous.exploration.motion.traveling_forces` does, their sum and the
displacement rule's step, in one call of
:func:`~tether.continuous.exploration.substep_kernels.total_force_kernel` (the same kernels
in the same order, so the same bits). Used when :func:`tether.jit.enabled` and the exact
eigensolver runs; the reference is the chain itself.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from tether.continuous.connectivity.strategy import ConnectivityStrategy

#: adjust(q, v, f_lambda, f_i) -> f_i: a change of the external force after the kernel
Adjust = Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray]
#: forces(q, v, cache) -> (f_lambda + f_i, f_lambda, displacement step)
Forces = Callable[[np.ndarray, np.ndarray, Any], tuple[np.ndarray, np.ndarray, float]]


def fused_total_force(
    strategy: ConnectivityStrategy,
    travel: tuple,
    gains: tuple[float, ...],
    adjust: Adjust | None = None,
) -> Forces:
    """``forces(q, v, cache)`` for one control period.

    Parameters
    ----------
    strategy
        The strategy integrating the period (its Table 2 parameters, the integrator's
        mass and displacement bound).
    travel, gains
        The traveling kernel's arguments a period fixes
        (:func:`tether.continuous.exploration.motion.travel_args`) and its gains
        (:func:`tether.continuous.exploration.motion.travel_gains`).
    adjust
        If the strategy's external force is the traveling force changed afterwards (some
        rows replaced), that change: it gets the kernel's ``f_lambda`` and ``f_i`` and
        returns the external force; the sum and the step are then made from it as the
        reference makes them
        (:func:`~tether.continuous.connectivity.dynamics_kernels.displacement_kernel`).
        Without it the fused call would leave the change out.
    """
    from tether.continuous.connectivity.dynamics_kernels import displacement_kernel
    from tether.continuous.exploration.substep_kernels import total_force_kernel

    conn, integ = strategy.conn, strategy.integ
    potential = (float(conn.lambda2_min), float(conn.lambda2_null), float(conn.potential_gain))
    gains = tuple(float(g) for g in gains)
    mass, delta = float(integ.mass_kg), float(integ.max_step_m)

    def forces(q: np.ndarray, v: np.ndarray, cache: Any) -> tuple[np.ndarray, np.ndarray, float]:
        graph, lam, nu = cache
        arrays = (graph.pairs, graph.pair_factor, graph.collision, graph.dP_di, graph.dP_dj,
                  graph.coll_pairs, graph.coll_unit, graph.coll_logd)  # fmt: skip
        total, h, f_lambda, f_ext = total_force_kernel(
            np.ascontiguousarray(q), np.ascontiguousarray(v), arrays,
            np.ascontiguousarray(nu, dtype=float), float(lam), potential, gains, *travel, mass,
            delta,
        )  # fmt: skip
        if adjust is not None:
            total = f_lambda + adjust(q, v, f_lambda, f_ext)
            h = displacement_kernel(np.ascontiguousarray(v), total, mass, delta)
        return total, f_lambda, float(h)

    return forces
