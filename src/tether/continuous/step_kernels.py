"""One compiled call per connectivity evaluation: weights, eigenpair and force (numba).

:func:`evaluate_fiedler_kernel` is what a sub-step of the exact strategies computes
through three Python calls -- :func:`tether.continuous.weights.compute_weights`,
:meth:`WeightedGraph.fiedler <tether.continuous.weights.WeightedGraph.fiedler>` from
the previous Fiedler vector and :func:`tether.continuous.gradient.exact_force` --
in one kernel call: :func:`~tether.continuous.kernels.evaluate_kernel`, then the
eigenpair as :func:`tether.graph.fiedler.fiedler` finds it for ``17 <= n <= 400``
robots (``method="auto"``: the certified small solver,
:func:`~tether.graph.small_kernels.small_fiedler_kernel`, and ``dsyevr`` when it
cannot certify; ``method="lapack"``: ``dsyevr`` always, through
:func:`~tether.graph.lapack_kernels.syevr_second_kernel`, the same call as scipy's
wrapper), its sign fixed by the guess, then optionally the force of eq. (17)
(:func:`~tether.continuous.force_kernels.exact_force_kernel`). The same routines in
the same order, so the same bits as the Python chain (``tests/test_step_kernels.py``).

The one branch left to Python: a lambda2 that may be at rounding level
(``fiedler``'s component check, a graph that is disconnected or nearly) or a
``dsyevr`` failure; the kernel then reports ``decided = False`` and the caller runs
the reference ``fiedler``.

Eigenpair: Fiedler (1973); the small solver: :mod:`tether.graph.small`; force: the
continuous-connectivity paper (Nestmeyer et al.), App. A, eqs. (17)-(18).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from tether.continuous.force_kernels import exact_force_kernel
from tether.continuous.kernels import evaluate_kernel
from tether.graph.fiedler import _TINY_REL as TINY_REL
from tether.graph.lapack_kernels import syevr_second_kernel
from tether.graph.small import OK
from tether.graph.small_kernels import small_fiedler_kernel


@njit(cache=True)
def _maybe_tiny(lam, lap, m):  # noqa: ANN001, ANN202
    """:func:`tether.graph.fiedler._maybe_tiny` with the dense Laplacian."""
    if m == 0:
        return True
    dmax = lap[0, 0]
    for r in range(1, lap.shape[0]):
        dmax = max(dmax, lap[r, r])
    return lam <= TINY_REL * dmax * (1.0 + 1e-6)


@njit(cache=True)
def fiedler_kernel(lap, m, guess, lapack, small, lwork, liwork):  # noqa: ANN001, ANN201, PLR0913
    """:func:`tether.graph.fiedler.fiedler` of a dense Laplacian with ``m`` links from
    ``guess`` (``17 <= n <= 400``): ``(decided, lambda2, vector, status)``.

    ``lapack``: ``dsyevr`` (``method="lapack"``), else the small solver with the settings
    ``small`` first (``"auto"``; ``status`` is its status, -1 if it did not run).
    ``decided = False``: the caller must run ``fiedler`` (lambda2 may be at rounding
    level, or ``dsyevr`` failed).
    """
    status = -1
    lam = 0.0
    vec = guess
    solved = False
    if not lapack:
        status, lam, vec, _, _ = small_fiedler_kernel(lap, guess, *small)
        solved = status == OK
    if not solved:
        val, vec, found, info = syevr_second_kernel(lap, lwork, liwork)
        if info != 0 or found != 1:
            return False, 0.0, guess.copy(), status
        lam = max(val, 0.0)
    if _maybe_tiny(lam, lap, m):
        return False, 0.0, guess.copy(), status
    if np.dot(vec, guess) < 0:
        vec = -vec
    return True, lam, vec, status


@njit(cache=True)
def evaluate_fiedler_kernel(  # noqa: ANN201, PLR0913
    q, rs_inner, rs, ro, ro_outer, rc, rc_outer, obstacles, points, tree, table, used, slack,
    field, order, guess, lapack, small, lwork, liwork, potential, with_force,
):  # noqa: ANN001  # fmt: skip
    """:func:`~tether.continuous.kernels.evaluate_kernel` (with the Laplacian), then
    :func:`fiedler_kernel` on it from ``guess``, then with ``with_force`` the force of
    the eigenpair (``potential = (lambda2_min, lambda2_null, gain)``).

    Returns ``evaluate_kernel``'s tuple, ``(decided, lambda2, vector, status)`` and the
    force (``(0, dim)`` when not made); ``decided = False`` and nothing after the
    weights when the clearance table must grow (``out[-1] < 0``).
    """
    n, dim = q.shape
    out = evaluate_kernel(q, rs_inner, rs, ro, ro_outer, rc, rc_outer, True, obstacles, points,
                          tree, table, used, slack, field, order)  # fmt: skip
    none = np.zeros((0, dim))
    if out[-1] < 0:
        return out, (False, 0.0, guess.copy(), -1), none
    pf, dP_di, dP_dj, _, coll, coll_pairs, coll_unit, coll_logd, pairs, _, lap, _ = out
    eigen = fiedler_kernel(lap, len(pairs), guess, lapack, small, lwork, liwork)
    if not (with_force and eigen[0]):
        return out, eigen, none
    force = exact_force_kernel(n, pairs, pf, coll, dP_di, dP_dj, coll_pairs, coll_unit,
                               coll_logd, eigen[2], eigen[1], potential[0], potential[1],
                               potential[2])  # fmt: skip
    return out, eigen, force


def warm_up(q: np.ndarray, nu: np.ndarray, small: tuple, obstacle_states: list) -> None:
    """Compile (or load) the kernels on a tiny team, with and without obstacles."""
    from tether.graph.lapack_kernels import warm_up as lapack_warm_up

    lapack_warm_up()
    for has, (points, tree, table, used, fld) in obstacle_states:
        for lapack in (False, True):
            evaluate_fiedler_kernel(q, 2.5, 6.0, 0.75, 1.75, 1.0, 2.5, has, points, tree,
                                    table, used, 0.25, fld, 1, nu, lapack, small, 78, 30,
                                    (0.0, 0.5, 1.0), True)  # fmt: skip
