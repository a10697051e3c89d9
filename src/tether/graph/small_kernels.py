"""Certified warm-started Fiedler pair of a small dense Laplacian (numba; imported lazily).

For teams up to a few hundred robots the Laplacian is a small dense matrix; between two
integrator sub-steps its Fiedler vector hardly moves. :func:`small_fiedler_kernel` runs
shifted inverse iteration from the previous vector with one ``L D L'`` factorization of
``L - tau I`` (no pivoting, ``O(n^3 / 3)``) and certifies the answer by Sylvester's law of
inertia (Parlett, *The Symmetric Eigenvalue Problem*, 1998, Sec. 3.3 and 4.6) and
Temple's inequality (ibid., Sec. 10.5), as the sparse solver of
:mod:`tether.graph.warm` does; rounding is accounted for by the backward error of the
factorization (Higham, *Accuracy and Stability of Numerical Algorithms*, 2nd ed.,
Thm. 9.3: ``L D L' = A + E`` with ``|E| <= gamma_n |L| |D| |L'|``). Used by
:func:`tether.graph.fiedler.fiedler` with ``method="small"``; when the certificate
fails the caller falls back to LAPACK ``dsyevr``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, uint64

#: status codes of :func:`small_fiedler_kernel` (0: certified)
OK, BAD_GUESS, TINY, BREAKDOWN, INERTIA, NO_CONVERGENCE = 0, 1, 2, 3, 4, 5


@njit(cache=True)
def _matvec(lap, x, out):  # noqa: ANN001, ANN202
    """``out = lap @ x`` for a symmetric ``lap``, as a sum of its rows (vectorised axpys)."""
    n = len(x)
    out[:] = 0.0
    for j in range(n):
        row = lap[j]
        xj = x[j]
        for i in range(n):
            out[i] += xj * row[i]


@njit(cache=True)
def _ldlt(lap, tau, f, d):  # noqa: ANN001, ANN202
    """``L D L'`` of ``lap - tau I`` without pivoting: ``L`` below ``f``'s diagonal, ``L'`` above.

    Returns ``(negative pivots, eta)`` with ``eta >= ||E||_2`` for the backward error
    ``E = L D L' - (lap - tau I)`` of the computed factors (Higham's
    ``gamma_n || |L| |D| |L'| ||_2``, with ``gamma`` doubled, bounded by
    ``|| |L| |D|^(1/2) ||_F^2``), or ``(-1, inf)`` when a pivot is zero or not finite.
    """
    n = len(d)
    for i in range(n):
        f[i] = lap[i]
        f[i, i] -= tau
    flat = f.ravel()  # unsigned offsets: no negative-index wrap-around, so loops vectorise
    negative = 0
    bound = 0.0
    for k in range(n):
        dk = f[k, k]
        if not (dk != 0.0 and math.isfinite(dk)):
            return -1, np.inf
        d[k] = dk
        if dk < 0.0:
            negative += 1
        inv = 1.0 / dk
        for i in range(k + 1, n):  # Schur complement, upper triangle, row by row
            t = f[k, i] * inv
            if t != 0.0:
                a, b = uint64(i * n + i), uint64(k * n + i)
                for j in range(uint64(n - i)):
                    flat[a + j] -= t * flat[b + j]
        col = 1.0
        for i in range(k + 1, n):
            lik = f[k, i] * inv
            f[k, i] = lik
            f[i, k] = lik
            col += lik * lik
        bound += abs(dk) * col
    if not math.isfinite(bound):
        return -1, np.inf
    u = 2.0**-53
    gamma = 2.0 * (n + 1) * u / (1.0 - (n + 1) * u)
    return negative, gamma * bound


@njit(cache=True)
def _solve(f, d, x):  # noqa: ANN001, ANN202
    """``x <- (L D L')^{-1} x`` with the factors of :func:`_ldlt` (column-oriented sweeps)."""
    n = len(d)
    for k in range(n - 1):  # L z = x: column k of L is row k of L'
        xk = x[k]
        if xk != 0.0:
            a = x[k + 1 :]
            b = f[k, k + 1 :]
            for i in range(n - 1 - k):
                a[i] -= b[i] * xk
    for k in range(n):
        x[k] /= d[k]
    for k in range(n - 1, 0, -1):  # L' y = z: column k of L' is row k of L
        xk = x[k]
        if xk != 0.0:
            a = x[:k]
            b = f[k, :k]
            for i in range(k):
                a[i] -= b[i] * xk


@njit(cache=True)
def _center_normalize(x):  # noqa: ANN001, ANN202
    """``x <- (x - mean x) / ||x - mean x||``; returns the norm before scaling."""
    n = len(x)
    mean = 0.0
    for i in range(n):
        mean += x[i]
    mean /= n
    norm = 0.0
    for i in range(n):
        x[i] -= mean
        norm += x[i] * x[i]
    norm = math.sqrt(norm)
    if norm > 0.0 and math.isfinite(norm):
        for i in range(n):
            x[i] /= norm
    return norm


@njit(cache=True)
def _rayleigh(lap, x, lx):  # noqa: ANN001, ANN202
    """Rayleigh quotient ``x' L x`` of a unit ``x`` and its residual's squared norm."""
    _matvec(lap, x, lx)
    n = len(x)
    theta = 0.0
    for i in range(n):
        theta += x[i] * lx[i]
    res = 0.0
    for i in range(n):
        e = lx[i] - theta * x[i]
        res += e * e
    return theta, res


@njit(cache=True)
def _ritz_low(a, b, c, g):  # noqa: ANN001, ANN202
    """Smaller Ritz value and its coefficients on the span of two unit vectors ``p, x``.

    ``a = p'Lp``, ``b = p'Lx``, ``c = x'Lx``, ``g = p'x``: the smaller root ``mu`` of
    ``det([[a, b], [b, c]] - mu [[1, g], [g, 1]]) = 0`` and ``(alpha, beta)`` with
    ``(alpha p + beta x)`` its Ritz vector; ``mu = inf`` when the two are parallel.
    """
    s = 1.0 - g * g
    if not s > 1e-8:
        return np.inf, 0.0, 1.0
    h = a + c - 2.0 * b * g
    disc = max(h * h - 4.0 * s * (a * c - b * b), 0.0)
    mu = (h - math.sqrt(disc)) / (2.0 * s)
    alpha, beta = b - mu * g, mu - a  # first row of the pencil, (a - mu) alpha' + ... = 0
    if abs(alpha) + abs(beta) < 1e-300:
        alpha, beta = mu - c, b - mu * g
    return mu, alpha, beta


@njit(cache=True)
def small_fiedler_kernel(  # noqa: ANN201, PLR0913
    lap, guess, shift_rel, tiny_rel, tol_rel, vec_tol, max_iter, max_factor
):  # noqa: ANN001
    """``(status, lambda2, vector, solves, factorizations)`` of the dense Laplacian ``lap``.

    1. ``x``: the guess, zero-mean and unit. The Rayleigh quotient of any such vector
       bounds lambda2 from above (Courant-Fischer on the complement of the constant
       vector); ``upper`` is the best so far. ``upper <= tiny_rel * max_i L_ii``:
       status ``TINY`` (a disconnected graph, or nearly: the caller's exact solver and
       component check decide).
    2. ``tau = upper (1 + rel)`` (``rel = shift_rel``); ``L - tau I = L D L' - E``.
       Exactly two negative pivots mean ``L - tau I + E`` has exactly two negative
       eigenvalues (Sylvester), so by Weyl ``lambda3 >= tau - eta`` with
       ``eta >= ||E||_2``. More than two (``lambda3 < tau``: the guess is closer to
       lambda3's vector, or the gap is small): once ``rel`` is divided by 100 and
       ``L - tau I`` factored again, then status ``INERTIA``.
    3. Shifted inverse iteration on the complement of the constant vector. With the
       Rayleigh quotient ``theta`` and residual ``r = ||L x - theta x||`` of the unit
       iterate, ``gap = tau - eta - theta > 0`` bounds ``lambda3 - theta`` from below,
       so Temple's inequality gives ``theta - r^2 / gap <= lambda2 <= theta`` and the
       angle to the Fiedler vector is at most ``r / gap`` (Davis-Kahan). It returns
       once ``r^2 / gap <= tol_rel * theta`` and ``r`` is at rounding level
       (``floor = 4 eps sqrt(n) max_i L_ii``) on two solves in a row, or stopped
       improving with ``r <= max(floor, vec_tol gap)``.
    4. The shift moves (a new factorization at a smaller ``upper``) when the residual
       falls by less than ten times per solve (``upper = theta``, or ``rel`` divided
       by 100 once ``theta`` no longer moves: lambda3 is close), or when ``theta``
       rises (the iterate turns towards lambda3's vector, closer to ``tau``): then
       ``upper`` is the smaller Ritz value on the last two iterates, whose span holds
       most of both vectors, and the iterate its Ritz vector.

    At most ``max_iter`` solves and ``max_factor`` factorizations (else
    ``NO_CONVERGENCE`` or ``INERTIA``). The vector is unit, zero-mean, its sign not fixed.
    """
    n = len(guess)
    x = guess.astype(np.float64)
    if n < 2 or lap.shape[0] != n or not _center_normalize(x) > 0.0:
        return BAD_GUESS, 0.0, x, 0, 0
    lx = np.empty(n)
    upper, _ = _rayleigh(lap, x, lx)
    top = 0.0
    for i in range(n):
        top = max(top, lap[i, i])
    if not upper > tiny_rel * top:
        return TINY, upper, x, 0, 0
    floor = 4.0 * 2.0**-52 * math.sqrt(n) * top
    f = np.empty((n, n))
    d = np.empty(n)
    prev = np.empty(n)
    rel = shift_rel
    tau, eta, theta_prev = 0.0, 0.0, upper
    factors, solves, since = 0, 0, 0
    factor, retried = True, False
    last = np.inf
    while solves < max_iter:
        if factor:
            if factors == max_factor:
                return INERTIA, upper, x, solves, factors
            tau = upper * (1.0 + rel)
            negative, eta = _ldlt(lap, tau, f, d)
            factors += 1
            if negative < 0:
                return BREAKDOWN, upper, x, solves, factors
            if negative > 2:  # lambda3 < tau: only a shift in [theta0, lambda3) can work
                if retried:
                    return INERTIA, upper, x, solves, factors
                retried = True
                rel *= 0.01
                continue
            if negative < 2:  # impossible in exact arithmetic (0 and lambda2 < tau)
                return INERTIA, upper, x, solves, factors
            factor = False
            since = 0
            last = np.inf
        prev[:] = x
        _solve(f, d, x)
        solves += 1
        since += 1
        if not _center_normalize(x) > 0.0:
            return BREAKDOWN, upper, x, solves, factors
        theta, res = _rayleigh(lap, x, lx)
        r = math.sqrt(res)
        gap = tau - eta - theta
        if theta > 0.0 and gap > 0.0 and res <= tol_rel * theta * gap:
            if (r <= floor and last <= floor) or (r >= 0.7 * last and r <= vec_tol * gap):
                return OK, theta, x, solves, factors
        if theta > theta_prev:  # turning towards lambda3: Ritz pair on {prev, x}
            b, g = 0.0, 0.0
            for i in range(n):
                b += prev[i] * lx[i]
                g += prev[i] * x[i]
            mu, alpha, beta = _ritz_low(theta_prev, b, theta, g)
            if mu < upper * (1.0 - rel):
                for i in range(n):
                    x[i] = alpha * prev[i] + beta * x[i]
                if not _center_normalize(x) > 0.0:
                    return BREAKDOWN, upper, x, solves, factors
                theta, res = _rayleigh(lap, x, lx)
                r = math.sqrt(res)
                if theta < upper:
                    upper = theta
                    factor = True
        elif since >= 2 and r > 0.1 * last:  # slow: a closer shift
            if theta < upper * (1.0 - rel):
                upper = theta
            else:  # theta has converged: lambda3 is close, move tau towards it
                rel *= 0.01
            factor = True
        theta_prev = theta
        last = r
    return NO_CONVERGENCE, upper, x, solves, factors


def warm_up() -> None:
    """Compile (or load from numba's cache) the kernel on a 3-node path."""
    lap = np.array([[1.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]])
    small_fiedler_kernel(lap, np.array([-1.0, 0.1, 1.0]), 1e-3, 1e-9, 1e-14, 1e-10, 30, 4)
