"""Certified warm-started Fiedler solver for large teams.

Between two control steps a team's Fiedler vector hardly changes, so the
previous one is an excellent start for shifted inverse iteration; one sparse
``L D L'`` factorization both certifies the shift (by Sylvester's inertia) and
solves. Used by :func:`tether.graph.fiedler.fiedler` with ``method="warm"``.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import identity
from scipy.sparse.linalg import splu

from tether.graph.structure import laplacian


def warm_fiedler(
    n: int,
    pairs: np.ndarray,
    weights: np.ndarray | None,
    guess: np.ndarray,
    *,
    shift_rel: float = 1e-2,
    tol_rel: float = 1e-10,
    max_iter: int = 12,
    retries: int = 2,
) -> tuple[float, np.ndarray] | None:
    """lambda2 and Fiedler vector by inverse iteration warm-started from ``guess``, certified.

    With ``x0`` the guess made zero-mean and unit, its Rayleigh quotient
    ``theta0 = x0' L x0`` bounds lambda2 from above (Courant-Fischer on the
    complement of the constant vector), so the shift ``tau = theta0 (1 +
    shift_rel)`` lies above lambda2. One sparse ``L D L'`` factorization of
    ``L - tau I`` (SuperLU with a symmetric fill-reducing ordering and
    diagonal pivots) serves twice:

    * its pivots' signs give the inertia (Sylvester's law): exactly two
      negative pivots mean exactly the eigenvalues ``0`` and lambda2 lie
      below ``tau``, so ``lambda3 > tau``;
    * shifted inverse iteration on the complement of the constant vector
      then converges to the Fiedler vector at the rate
      ``(tau - lambda2) / (lambda3 - tau)`` per solve.

    It stops when the Rayleigh quotient ``theta < tau`` and its residual
    ``r = ||L x - theta x||`` satisfy Temple's inequality
    ``theta - lambda2 <= r^2 / (lambda3 - theta) < r^2 / (tau - theta)
    <= tol_rel * theta``; since also ``lambda2 <= theta``, the returned
    ``theta`` is within ``tol_rel`` (relative) of lambda2. With more than two
    negative pivots (``lambda3 < tau``: a small spectral gap or a poor guess)
    the shift moves ten times closer to ``theta0`` up to ``retries`` times.

    Returns
    -------
    (lambda2, vector) or None
        ``None`` when the answer cannot be certified (no factorization,
        wrong inertia, no convergence in ``max_iter`` solves, lambda2 not
        positive); callers then use an exact solver.
    """
    x = np.asarray(guess, dtype=float) - float(np.mean(guess))
    norm = float(np.linalg.norm(x))
    if n < 2 or len(x) != n or not norm > 0:
        return None
    x /= norm
    pairs = np.asarray(pairs, dtype=np.intp).reshape(-1, 2)
    if weights is not None:  # links of zero weight do not connect
        keep = np.asarray(weights) > 0
        pairs, weights = pairs[keep], np.asarray(weights, dtype=float)[keep]
    lap = laplacian(n, pairs, weights).tocsc()
    theta0 = float(x @ (lap @ x))
    if not theta0 > 0:
        return None
    eye = identity(n, format="csc")
    rel = shift_rel
    for _ in range(retries + 1):
        tau = theta0 * (1.0 + rel)
        try:
            lu = splu(
                (lap - tau * eye).tocsc(),
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
            break
        if negative < 2:  # impossible in exact arithmetic (0 and lambda2 < tau)
            return None
        rel *= 0.1
    else:
        return None
    v = x
    for _ in range(max_iter):
        y = lu.solve(v)
        y -= y.mean()
        v = y / np.linalg.norm(y)
        lv = lap @ v
        theta = float(v @ lv)
        res = float(np.linalg.norm(lv - theta * v))
        if 0 < theta < tau and res * res <= tol_rel * theta * (tau - theta):
            if float(v @ guess) < 0:
                v = -v
            return theta, v
    return None
