"""Certified warm-started Fiedler solver for large teams.

Between two control steps a team's Fiedler vector hardly changes, so the
previous one is an excellent start; one sparse ``L D L'`` factorization of
``L - tau I`` both certifies a lower bound ``tau`` on lambda3 (by Sylvester's
inertia) and preconditions the iteration. A :class:`WarmState` keeps that
factorization between calls: while the graph stays close to the factored one
(Weyl's inequality), the bound still holds, shifted down by the change, and the
old factorization still preconditions well, so most steps need no factorization
at all. Used by :func:`tether.graph.fiedler.fiedler` with ``method="warm"``.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse.linalg import splu

from tether.graph.links import Links, change_bound

#: relative slack on the Weyl bound, for the rounding of the weights' sums and of ``L``
_ROUNDING_REL = 1e-10


class WarmState:
    """What :func:`warm_fiedler` keeps between calls on a changing graph.

    The graph ``L_f`` of the last factorization (its :class:`~tether.graph.links.Links`),
    the factorization of ``L_f - tau I`` and its certificate ``lambda3(L_f) > tau``.

    The shift of a new factorization, ``tau = theta0 (1 + rel)`` above the guess's
    Rayleigh quotient, is a trade: a larger ``rel`` leaves room for more change
    before the next factorization, but reaches past lambda3 (a wasted factorization)
    when the spectral gap is small. ``rel`` is ``3 drift / theta0``, room for about
    three more steps like the one that invalidated the last factorization, when that
    stays below ``SHIFT_MAX`` and half the smallest ``rel`` seen to reach past lambda3
    (``gap_rel``, relaxed by 5 % at each factorization since the spectrum
    moves); otherwise, when a step changes the graph by more than the gap (reuse is
    hopeless), the solver's own small shift, which converges fastest.
    Results depend on the state only within the certified tolerances.

    One state per sequence of graphs (a strategy's run); a state is never shared
    between runs, so a run's results do not depend on what ran before it.
    """

    SHIFT_MAX = 2.0

    def __init__(self, shift_rel: float = 0.1) -> None:
        self.shift_rel = shift_rel
        self.gap_rel = float("inf")
        self.links: Links | None = None
        self.lu = None
        self.tau = float("nan")
        self.factorizations = 0
        self.reuses = 0

    def clear(self) -> None:
        """Forget the factorization (the next call factors afresh)."""
        self.links, self.lu, self.tau = None, None, float("nan")

    def next_shift(self, drift_rel: float | None, default: float) -> float:
        """``rel`` for the next factorization after a change of ``drift_rel`` (relative)."""
        if drift_rel is not None:
            self.shift_rel = 3.0 * drift_rel
        limit = min(self.SHIFT_MAX, 0.5 * self.gap_rel)
        return max(self.shift_rel, default) if self.shift_rel <= limit else default


def warm_fiedler(
    n: int,
    pairs: np.ndarray,
    weights: np.ndarray | None,
    guess: np.ndarray,
    *,
    state: WarmState | None = None,
    shift_rel: float = 1e-2,
    tol_rel: float = 1e-10,
    vec_tol: float = 1e-5,
    max_iter: int = 12,
    reuse_iter: int = 4,
    retries: int = 2,
) -> tuple[float, np.ndarray] | None:
    """lambda2 and Fiedler vector by a certified iteration warm-started from ``guess``.

    With ``x`` unit and zero-mean, its Rayleigh quotient ``theta = x' L x``
    bounds lambda2 from above (Courant-Fischer on the complement of the constant
    vector). Given a lower bound ``rho <= lambda3`` with ``theta < rho``, Temple's
    inequality with the residual ``r = ||L x - theta x||`` gives ``theta - lambda2
    <= r^2 / (lambda3 - theta) <= r^2 / (rho - theta)``, and the Davis-Kahan
    theorem ``sin angle(x, nu2) <= r / (rho - theta)`` (Parlett, *The Symmetric
    Eigenvalue Problem*, Thms. 10.6.1 and 11.7.1). An answer is returned only when
    ``r^2 <= tol_rel theta (rho - theta)`` (lambda2 to ``tol_rel``, relative) and
    ``r <= vec_tol (rho - theta)`` (the vector to an angle of ``vec_tol``).

    ``rho`` comes from a sparse ``L D L'`` factorization of ``L_f - tau I``
    (SuperLU, symmetric fill-reducing ordering, diagonal pivots): exactly two
    negative pivots mean (Sylvester's law of inertia) that only ``0`` and
    lambda2 lie below ``tau``, so ``lambda3(L_f) > tau``. For the graph ``L``
    itself, ``rho = tau - ||L - L_f||_2`` (Weyl; the norm bounded by
    :func:`tether.graph.links.change_bound`). Without a usable ``state``, ``L_f =
    L`` is factored now with ``tau = theta0 (1 + shift_rel)`` (``theta0``: the
    guess's quotient), ten times closer to ``theta0`` up to ``retries`` times
    while the inertia shows more than two eigenvalues below ``tau``; with a
    ``state`` the last factorization is tried first (``reuse_iter`` iterations)
    and a new one is kept in it.

    The iteration is LOBPCG with one vector (Knyazev 2001): the Rayleigh-Ritz
    minimum over ``x``, the preconditioned residual ``(L_f - tau I)^{-1} r`` and
    the previous step, all kept orthogonal to the constant vector. With ``L_f = L``
    the subspace contains the shifted inverse iteration's next vector.

    Returns
    -------
    (lambda2, vector) or None
        ``None`` when the answer cannot be certified (no factorization,
        wrong inertia, no convergence in ``max_iter`` iterations, lambda2 not
        positive); callers then use an exact solver. The vector's sign follows
        ``guess``.
    """
    x = np.asarray(guess, dtype=float) - float(np.mean(guess))
    norm = float(np.linalg.norm(x))
    if n < 2 or len(x) != n or not norm > 0:
        return None
    x /= norm
    links = Links.from_pairs(n, pairs, weights)
    lx = links.product(x)
    theta0 = float(x @ lx)
    if not theta0 > 0:
        return None
    out = None
    drift_rel = None
    if state is not None and state.links is not None and state.links.n == n:
        drift = change_bound(state.links, links)
        rho = state.tau - drift * (1.0 + _ROUNDING_REL) - _slack(links, state.links)
        if rho > theta0:  # else the graph moved out of reach (the quotient must end below rho)
            out = _lobpcg(links, state.lu.solve, x, lx, rho, tol_rel, vec_tol, reuse_iter)
        if out is not None:
            state.reuses += 1
        drift_rel = drift / theta0
    if out is None:
        rel = shift_rel if state is None else state.next_shift(drift_rel, shift_rel)
        factored = _factor(links, theta0, rel, retries, state)
        if factored is None:
            return None
        lu, tau = factored
        if state is not None:
            state.links, state.lu, state.tau = links, lu, tau
            state.factorizations += 1
        out = _lobpcg(links, lu.solve, x, lx, tau - _slack(links), tol_rel, vec_tol, max_iter)
        if out is None:
            return None
    theta, v = out
    if float(v @ guess) < 0:
        v = -v
    return theta, v


def _slack(*graphs: Links) -> float:
    """Rounding of ``L`` and of its products: a few ulps of the largest degree."""
    return 64.0 * np.finfo(float).eps * max(g.max_degree for g in graphs)


def _factor(
    links: Links, theta0: float, rel: float, retries: int, state: WarmState | None
) -> tuple | None:
    """``(lu, tau)``: ``L - tau I`` factored with exactly two negative pivots, or None.

    A shift that reaches past lambda3 is recorded in ``state.gap_rel``.
    """
    if state is not None:
        state.gap_rel *= 1.05
    for _ in range(retries + 1):
        tau = theta0 * (1.0 + rel)
        try:
            lu = splu(
                links.shifted(tau),
                permc_spec="MMD_AT_PLUS_A",
                diag_pivot_thresh=0.0,
                options={"SymmetricMode": True},
            )
        except RuntimeError:  # exactly singular
            return None
        pivots = lu.U.diagonal()
        if not np.array_equal(lu.perm_r, lu.perm_c) or not np.all(np.isfinite(pivots)):
            return None
        negative = int(np.count_nonzero(pivots < 0))
        if negative == 2:
            return lu, tau
        if negative < 2:  # impossible in exact arithmetic (0 and lambda2 < tau)
            return None
        if state is not None:
            state.gap_rel = min(state.gap_rel, rel)
        rel *= 0.1
    return None


def _lobpcg(
    links: Links,
    solve,  # noqa: ANN001
    x: np.ndarray,
    lx: np.ndarray,
    rho: float,
    tol_rel: float,
    vec_tol: float,
    max_iter: int,
) -> tuple[float, np.ndarray] | None:
    """Certified ``(theta, x)`` after at most ``max_iter`` LOBPCG steps, else None.

    ``x`` unit and zero-mean, ``lx = L x``; ``rho <= lambda3`` (see :func:`warm_fiedler`).
    The certificate is computed from ``x`` and an explicit ``L x`` each time.
    """
    p = None
    for it in range(max_iter + 1):
        theta = float(x @ lx)
        r = lx - theta * x
        res = float(np.linalg.norm(r))
        gap = rho - theta
        if theta > 0 and gap > 0 and res * res <= tol_rel * theta * gap and res <= vec_tol * gap:
            return theta, x
        if it == max_iter:
            return None
        basis, images = [x], [lx]
        for y in (solve(r), p):
            if y is None:
                continue
            size = float(np.linalg.norm(y))
            y = y - float(np.mean(y))
            for _ in range(2):  # twice is enough (Giraud et al. 2005)
                for b in basis:
                    y -= float(b @ y) * b
            ny = float(np.linalg.norm(y))
            if not ny > 1e-10 * size:  # (almost) in the span already
                continue
            y /= ny
            basis.append(y)
            images.append(links.product(y))
        if len(basis) == 1:
            return None  # the correction lies along x: no progress possible
        s = np.column_stack(basis)
        h = s.T @ np.column_stack(images)
        _, vecs = np.linalg.eigh(0.5 * (h + h.T))
        c = vecs[:, 0]
        p = s[:, 1:] @ c[1:]
        x = s @ c
        x -= float(np.mean(x))
        x /= float(np.linalg.norm(x))
        lx = links.product(x)
    return None
