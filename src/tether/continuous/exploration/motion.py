"""Algorithm 2 of the continuous-connectivity paper: every robot's traveling force ``f_i``.

Connectors 0; the prime traveler ``f_travel`` (eq. (3)); secondary travelers
``rho(Theta(f_lambda_i, f_travel_i), Lambda_hat_i, sigma) f_travel`` (eqs. (4), (8), (14),
(15)); anchors ``f_anchor`` (eq. (7)). Robot ``i``'s force uses only its own state, path
and target, its ``f_lambda_i`` and ``Lambda_hat_i`` (decentralized). The numpy reference
is :func:`traveling_forces`; with the kernels on, one call of
:func:`tether.continuous.exploration.tracking_kernels.traveling_kernel` (the same bits).
"""

from __future__ import annotations

import numpy as np

from tether import jit
from tether.continuous.exploration.params import MultiTargetParams
from tether.continuous.exploration.roles import SECONDARY, RolePlanner
from tether.continuous.exploration.travel import alignment, anchor_force, rho, travel_force


def traveling_forces(
    q: np.ndarray,
    v: np.ndarray,
    f_lambda: np.ndarray,
    planner: RolePlanner,
    lambda_hat: np.ndarray,
    p: MultiTargetParams,
    anchors: tuple[np.ndarray, np.ndarray] | None = None,
) -> np.ndarray:
    """``f_i`` of Algorithm 2 for every robot, ``(n, dim)``.

    Connectors 0; the prime ``f_travel`` (eq. (3)); secondaries
    ``rho(Theta(f_lambda_i, f_travel_i), Lambda_hat_i, sigma) f_travel`` (eqs.
    (4), (8), (14), (15)); anchors ``f_anchor`` (eq. (7)). Robot ``i``'s row
    uses only its own state, path and target, ``f_lambda_i`` and ``Lambda_hat_i``.
    ``anchors``: the anchored robots and their targets, if the caller has them.
    """
    if anchors is None:
        held = np.flatnonzero(planner.anchored())
        anchors = held, anchor_targets(planner, held, q.shape[1])
    if jit.enabled():
        return _traveling_forces_kernel(q, v, f_lambda, planner, lambda_hat, p, anchors)
    f = np.zeros_like(q)
    role = planner.role
    trav, paths = planner.path_set()  # the travelers: prime and secondaries on their way
    if len(trav):
        ps = paths.states(q[trav], p.v_cruise_mps)
        ft = travel_force(q[trav], v[trav], ps, kp=p.kp_n_per_m, kv=p.kv_ns_per_m,
                          mass_kg=p.mass_kg, damping_ns_per_m=p.damping_ns_per_m,
                          max_force_n=p.max_travel_force_n)  # fmt: skip
        sec = role[trav] == SECONDARY
        scale = np.ones(len(trav))
        scale[sec] = rho(alignment(f_lambda[trav[sec]], ft[sec]), lambda_hat[trav[sec]], p.sigma)
        f[trav] = scale[:, None] * ft
    held, targets = anchors
    if len(held):
        f[held] = anchor_force(q[held], targets, p.rz_m, p.kz_n, p.anchor_force_bound_n())
    return f


def anchor_targets(planner: RolePlanner, robots: np.ndarray, dim: int) -> np.ndarray:
    return planner.targets_of(robots) if len(robots) else np.zeros((0, dim))


def _traveling_forces_kernel(
    q: np.ndarray,
    v: np.ndarray,
    f_lambda: np.ndarray,
    planner: RolePlanner,
    lambda_hat: np.ndarray,
    p: MultiTargetParams,
    anchors: tuple[np.ndarray, np.ndarray],
) -> np.ndarray:
    """:func:`traveling_forces` in one call of the compiled kernel (same bits)."""
    from tether.continuous.exploration.tracking_kernels import traveling_kernel

    return traveling_kernel(np.ascontiguousarray(q), np.ascontiguousarray(v),
                            np.ascontiguousarray(f_lambda),
                            *travel_args(planner, lambda_hat, p, anchors),
                            *travel_gains(p))  # fmt: skip


def travel_args(
    planner: RolePlanner,
    lambda_hat: np.ndarray,
    p: MultiTargetParams,
    anchors: tuple[np.ndarray, np.ndarray],
) -> tuple:
    """The traveling kernel's arguments after ``f_lambda`` that a control period fixes.

    The travelers, which of them are secondaries, ``Lambda_hat``, the anchored robots
    and their targets, the paths' kernel arrays, ``v_cruise``, the tie width and
    :func:`~tether.world.clearance.einsum_order`.
    """
    from tether.continuous.exploration.tracking import TIE_M
    from tether.world.clearance import einsum_order

    trav, paths = planner.path_set()
    trav = trav.astype(np.int64)
    held, targets = anchors[0].astype(np.int64), anchors[1]
    path = paths.kernel_args() if len(trav) else _NO_PATHS
    return (trav, planner.role[trav] == SECONDARY, np.ascontiguousarray(lambda_hat, dtype=float),
            held, np.ascontiguousarray(targets, dtype=float), path, float(p.v_cruise_mps), TIE_M,
            einsum_order())  # fmt: skip


def travel_gains(p: MultiTargetParams) -> tuple[float, ...]:
    """``(kp, kv, mass, damping, max_force, sigma, Rz, kz, anchor_max)`` as the traveling
    kernel takes them."""
    return (p.kp_n_per_m, p.kv_ns_per_m, p.mass_kg, p.damping_ns_per_m, p.max_travel_force_n,
            p.sigma, p.rz_m, p.kz_n, p.anchor_force_bound_n())  # fmt: skip


_i0, _f1, _f2 = np.zeros(1, np.int64), np.zeros(0), np.zeros((0, 3))
#: path arguments of the traveling kernel when nobody travels (the types of a PathSet's)
_NO_PATHS = (_i0, _f2, _f2, _f1, _f1, _f1, _f2, _f2, _f2, _f2, _f1, _f1, _f1, _i0[:0])
