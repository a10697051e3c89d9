"""Local Steering Strategy for non-communicating robots.

Source: F. Kerestecioglu and A. Cezayirli, "Connected Navigation of
Non-Communicating Mobile Agents" (sections III-IV). Each robot moves using only
the noisy relative positions ``x_k^i`` of the robots it senses (no labels, no
messages):

* a desired direction from the gradient step (14) of a cost: the desired
  distance cost (13), giving eq. (15), or the farthest-neighbour cost (12);
* the step magnitude then shrunk to satisfy constraint (1) for the robots in
  ``S_ip`` (the step does not approach them) and constraint (2) for those in
  ``S_iq`` (it does), with ``d_m = d_max - delta_r``.

With bounded measurement errors (radial ``delta_r``, angular ``delta_theta``)
we evaluate both constraints for the worst true position consistent with each
measurement, which is what the paper's Theorem 1 needs to hold with noise:

* a neighbour is in ``S_iq`` only if the step approaches it for every true
  position in its uncertainty cone: ``phi_k + delta_theta < 90 deg``, where
  ``phi_k`` is the angle between the step and the measurement;
* (2) for all such positions: ``||x|| <= (||m_k|| - delta_r) cos(phi_k + delta_theta)``;
* (1): ``||x|| <= (d_m - max_p ||m_p||) / 2`` (the paper's form; ``d_m``
  already absorbs the radial error).

With ``delta_r = delta_theta = 0`` these are exactly the paper's (1) and (2).
Both constraints bound only the step's length for a given direction, and
shrinking a step never violates them, so a step can also be shortened for a
speed limit, obstacles, or the optional minimum separation.

All functions work on a whole team at once: measurements are given CSR-style
(``observer`` index per measurement, see :class:`tether.sensing.Observation`).
"""

from __future__ import annotations

from functools import cache
from types import ModuleType
from typing import Literal

import numpy as np

from tether import floats, jit
from tether.geometry import unit
from tether.graph import expand_rows

Cost = Literal["desired_distance", "farthest"]


def _segment_sum(values: np.ndarray, observer: np.ndarray, n: int) -> np.ndarray:
    out = np.zeros((n, values.shape[1]))
    np.add.at(out, observer, values)
    return out


def _segment_min(values: np.ndarray, observer: np.ndarray, n: int) -> np.ndarray:
    out = np.full(n, np.inf)
    np.minimum.at(out, observer, values)
    return out


def desired_steps(
    measured: np.ndarray,
    observer: np.ndarray,
    n: int,
    *,
    cost: Cost = "desired_distance",
    gamma: float = 0.2,
    d0_m: float = 8.0,
) -> np.ndarray:
    """Gradient step (14) of each robot's cost, from its measurements only.

    ``desired_distance`` (13): ``x = 2 gamma sum_k (||x_k|| - d0) x_k / ||x_k||`` (15).
    ``farthest`` (12): ``J = max_k ||x - x_k||``, whose gradient at ``x = 0`` gives
    ``x = gamma x_f / ||x_f||`` towards the farthest sensed robot ``f``.
    Robots that sense nobody get a zero step. For cost (13), with the compiled kernels
    (:func:`_use_kernel`), :func:`tether.silent.steering_kernels.desired_distance_kernel`
    adds the same terms in the same order (bit-identical).
    """
    if cost == "desired_distance" and _use_kernel(n) and measured.ndim == 2:
        return _kernels().desired_distance_kernel(
            np.ascontiguousarray(measured, dtype=float),
            np.asarray(observer, dtype=np.int64), int(n), float(gamma), float(d0_m),
        )  # fmt: skip
    dist = np.linalg.norm(measured, axis=1)
    direction = unit(measured)
    if cost == "desired_distance":
        terms = 2.0 * gamma * (dist - d0_m)[:, None] * direction  # eq. (15)
        return _segment_sum(terms, observer, n)
    if cost == "farthest":
        far = np.full(n, -1.0)
        np.maximum.at(far, observer, dist)
        is_far = dist >= far[observer]
        # first farthest measurement of each observer (ties: lowest index)
        first = np.full(n, -1)
        idx = np.nonzero(is_far)[0]
        first[observer[idx[::-1]]] = idx[::-1]
        out = np.zeros((n, measured.shape[1]))
        has = first >= 0
        out[has] = gamma * direction[first[has]]  # eq. (14) on cost (12)
        return out
    raise ValueError(f"unknown cost {cost!r}; expected 'desired_distance' or 'farthest'")


def step_bounds(
    directions: np.ndarray,
    measured: np.ndarray,
    observer: np.ndarray,
    n: int,
    *,
    d_max_m: float,
    radial_error_m: float = 0.0,
    angular_error_rad: float = 0.0,
    min_separation_m: float = 0.0,
) -> np.ndarray:
    """Largest step length each robot may take along its unit ``directions`` (``(n, dim)``).

    Implements constraints (1) and (2) robustly (module docstring). With
    ``min_separation_m > 0``, a robot whose step may approach a neighbour also
    keeps ``||x|| <= (||m_k|| - delta_r - s) / 2``, so two robots that sense
    each other never come closer than ``s``. Robots that sense nobody get ``inf``.
    """
    bound = _pair_bounds(
        directions[observer],
        measured,
        d_max_m=d_max_m,
        radial_error_m=radial_error_m,
        angular_error_rad=angular_error_rad,
        min_separation_m=min_separation_m,
    )
    return _segment_min(bound, observer, n)


def _pair_bounds(
    u: np.ndarray,
    measured: np.ndarray,
    *,
    d_max_m: float,
    radial_error_m: float,
    angular_error_rad: float,
    min_separation_m: float,
) -> np.ndarray:
    """Step-length bound for unit direction ``u[k]`` from one measurement ``measured[k]``."""
    d_m = d_max_m - radial_error_m  # definition of d_m (section III)
    dist = np.linalg.norm(measured, axis=1)
    cos_phi = np.einsum("kd,kd->k", u, unit(measured))
    phi = floats.arccos(np.clip(cos_phi, -1.0, 1.0))
    worst = phi + angular_error_rad
    in_q = worst < np.pi / 2  # S_iq: the step approaches k for every consistent position
    bound = np.where(
        in_q,
        (dist - radial_error_m) * floats.cos(np.minimum(worst, np.pi / 2)),  # constraint (2)
        0.5 * (d_m - dist),  # constraint (1)
    )
    if min_separation_m > 0:
        may_approach = phi - angular_error_rad < np.pi / 2
        sep = 0.5 * (dist - radial_error_m - min_separation_m)
        bound = np.where(may_approach, np.minimum(bound, sep), bound)
    return np.maximum(bound, 0.0)


#: below this many robots the kernel runs only if numba is loaded already (or
#: TETHER_JIT=on): loading numba (about a second) would cost a short small-team run more
#: than the kernel saves (about 2 ms per step at 20 robots)
KERNEL_MIN_ROBOTS = 200


@cache
def _kernels() -> ModuleType:
    """:mod:`tether.silent.steering_kernels`, imported on first use (it loads numba)."""
    from tether.silent import steering_kernels

    return steering_kernels


def _use_kernel(n: int) -> bool:
    """Whether :func:`constrained_steps` runs the compiled kernel for ``n`` robots."""
    if n == 0 or not jit.enabled():
        return False
    return n >= KERNEL_MIN_ROBOTS or jit.warm() or jit.mode() == "on"


def constrained_steps(
    desired: np.ndarray,
    measured: np.ndarray,
    observer: np.ndarray,
    *,
    d_max_m: float,
    radial_error_m: float = 0.0,
    angular_error_rad: float = 0.0,
    min_separation_m: float = 0.0,
    max_step_m: float = np.inf,
    search_directions: bool = False,
    indptr: np.ndarray | None = None,
) -> np.ndarray:
    """Steps that satisfy (1), (2) and the speed limit, as close to ``desired`` as allowed.

    By default (the paper's section IV) each desired step keeps its direction
    and is shortened. With ``search_directions``, each robot also considers
    heading straight at each robot it senses, and takes the candidate whose
    allowed step makes the most first-order progress ``<x, desired>`` on its
    cost (zero if none makes any). A robot whose desired direction is blocked
    by a neighbour at the edge of its range then closes on that neighbour
    instead of waiting, which relieves the tension that otherwise stalls a group
    spread near ``d_max`` (large ``d0``). Every candidate obeys (1)-(2), so
    Theorem 1 holds either way.

    With :func:`tether.jit.enabled` (and measurements grouped by observer, as an
    :class:`~tether.sensing.Observation` holds them), the compiled
    :mod:`tether.silent.steering_kernels` computes the same steps robot by robot.
    ``indptr``: the observation's CSR row pointers (``observer`` grouped by robot) if the
    caller has them, so they are not rebuilt.
    """
    n = len(desired)
    grouped = indptr is not None  # an Observation's CSR: measurements grouped by observer
    if indptr is None:
        indptr = np.concatenate([[0], np.cumsum(np.bincount(observer, minlength=n))])
    if _use_kernel(n) and (grouped or len(observer) < 2 or (np.diff(observer) >= 0).all()):
        return _kernels().constrained_steps_kernel(
            np.ascontiguousarray(desired, dtype=float),
            np.ascontiguousarray(measured, dtype=float).reshape(-1, desired.shape[1]),
            indptr.astype(np.int64), float(d_max_m), float(radial_error_m),
            float(angular_error_rad), float(min_separation_m), float(max_step_m),
            bool(search_directions),
        )  # fmt: skip
    length = np.linalg.norm(desired, axis=1)
    if search_directions:
        owner = np.concatenate([np.arange(n), observer])
        cand = np.concatenate([unit(desired), unit(measured)])
    else:
        owner, cand = np.arange(n), unit(desired)
    which, entry = expand_rows(indptr, owner)
    pair = _pair_bounds(
        cand[which],
        measured[entry],
        d_max_m=d_max_m,
        radial_error_m=radial_error_m,
        angular_error_rad=angular_error_rad,
        min_separation_m=min_separation_m,
    )
    allowed = np.minimum(
        np.minimum(length[owner], _segment_min(pair, which, len(owner))), max_step_m
    )
    if not search_directions:
        return cand * allowed[:, None]
    progress = allowed * np.einsum("kd,kd->k", cand, unit(desired)[owner])
    # best candidate per robot; ties keep the desired direction (listed first)
    order = np.lexsort((np.arange(len(owner)), -progress, owner))
    first = order[np.concatenate([[True], owner[order][1:] != owner[order][:-1]])]
    best = np.zeros(n, dtype=np.intp)
    best[owner[first]] = first
    steps = cand[best] * allowed[best][:, None]
    steps[progress[best] <= 0.0] = 0.0
    return steps


def team_steps(
    measured: np.ndarray,
    indptr: np.ndarray,
    leader: int,
    leader_step: np.ndarray,
    *,
    cost: Cost = "desired_distance",
    gamma: float = 0.2,
    d0_m: float = 8.0,
    d_max_m: float,
    radial_error_m: float = 0.0,
    angular_error_rad: float = 0.0,
    min_separation_m: float = 0.0,
    max_step_m: float = np.inf,
    search_directions: bool = False,
) -> np.ndarray:
    """One step of the Local Steering Strategy for a team led by robot ``leader``.

    The followers' desired steps (:func:`desired_steps`), the leader's replaced by
    ``leader_step`` (its step towards its trajectory), then :func:`constrained_steps`
    for everybody (the paper's section IV: the leader obeys (1)-(2) too). Measurements
    are an :class:`~tether.sensing.Observation`'s CSR rows (``indptr``, one row per
    robot). For cost (13), with the compiled kernels (:func:`_use_kernel`), one call
    of :func:`tether.silent.steering_kernels.team_steps_kernel` gives the same steps,
    bit for bit, as the kernels of the three steps.
    """
    n = len(indptr) - 1
    if cost == "desired_distance" and _use_kernel(n) and measured.ndim == 2:
        return _kernels().team_steps_kernel(
            np.ascontiguousarray(measured, dtype=float), indptr.astype(np.int64, copy=False),
            int(leader), np.asarray(leader_step, dtype=float), float(gamma), float(d0_m),
            float(d_max_m), float(radial_error_m), float(angular_error_rad),
            float(min_separation_m), float(max_step_m), bool(search_directions),
        )  # fmt: skip
    observer = np.repeat(np.arange(n), np.diff(indptr))
    desired = desired_steps(measured, observer, n, cost=cost, gamma=gamma, d0_m=d0_m)
    desired[leader] = leader_step
    return constrained_steps(desired, measured, observer, d_max_m=d_max_m,
                             radial_error_m=radial_error_m, angular_error_rad=angular_error_rad,
                             min_separation_m=min_separation_m, max_step_m=max_step_m,
                             search_directions=search_directions, indptr=indptr)  # fmt: skip


def satisfies_constraints(
    step: np.ndarray,
    rel_true: np.ndarray,
    *,
    d_max_m: float,
    tol: float = 1e-9,
) -> bool:
    """Check one robot's step against (1) or (2) for each neighbour's *true* position.

    The per-pair form used in the proof of Theorem 1: every neighbour ``k``
    satisfies either ``2||x|| + ||x_k|| <= d_max`` or ``||x||^2 <= x^T x_k``.
    Used by tests as an independent oracle.
    """
    if len(rel_true) == 0:
        return True
    x2 = float(step @ step)
    dist = np.linalg.norm(rel_true, axis=1)
    ok_p = 2.0 * np.sqrt(x2) + dist <= d_max_m + tol
    ok_q = x2 <= rel_true @ step + tol
    return bool(np.all(ok_p | ok_q))
