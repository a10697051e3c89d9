"""Certified warm-started Fiedler pair of a small dense Laplacian.

Between two integrator sub-steps a team's Fiedler vector hardly moves, and for teams up
to a few hundred robots the Laplacian is a small dense matrix. :func:`small_fiedler`
runs shifted inverse iteration from the previous vector with one ``L D L'``
factorization of ``L - tau I`` (no pivoting, ``n^3 / 3`` flops) and certifies that the
answer is the second eigenpair: by Sylvester's law of inertia (Parlett, *The Symmetric
Eigenvalue Problem*, 1998, Sec. 3.3) and Temple's inequality (ibid., Sec. 10.5), as the
sparse solver of :mod:`tether.graph.warm` does, with the rounding of the factorization
accounted for by its backward error (Higham, *Accuracy and Stability of Numerical
Algorithms*, 2nd ed., 2002, Thm. 9.3: the computed factors are exact for
``L - tau I + E`` with ``|E| <= gamma_n |L| |D| |L'|``). When it cannot certify,
:func:`tether.graph.fiedler.fiedler` falls back to LAPACK ``dsyevr``.

The algorithm (step by step in :func:`small_fiedler`):

1. ``x``: the guess, zero-mean and unit. The Rayleigh quotient of any such vector bounds
   lambda2 from above (Courant-Fischer on the complement of the constant vector);
   ``upper`` is the best so far. ``upper <= TINY_REL * max_i L_ii``: status ``TINY``
   (a disconnected graph, or nearly: the exact solver and the component check decide).
2. ``tau = upper (1 + rel)`` (``rel = SHIFT_REL``); the computed ``L D L'`` is
   ``L - tau I + E``. Exactly two negative pivots mean ``L - tau I + E`` has exactly
   two negative eigenvalues (Sylvester), so by Weyl ``lambda3 >= tau - eta`` with
   ``eta >= ||E||_2``. More than two (``lambda3 < tau``: the guess is closer to
   lambda3's vector, or the gap is tiny): ``rel`` is divided by 100 once and ``L - tau I``
   factored again, then status ``INERTIA``.
3. Shifted inverse iteration on the complement of the constant vector. With the Rayleigh
   quotient ``theta`` and residual ``r = ||L x - theta x||`` of the unit iterate,
   ``gap = tau - eta - theta > 0`` bounds ``lambda3 - theta`` from below, so Temple's
   inequality gives ``theta - r^2 / gap <= lambda2 <= theta`` and the angle to the
   Fiedler vector is at most ``r / gap`` (Davis-Kahan). It returns once
   ``r^2 / gap <= TOL_REL * theta`` and ``r`` is at rounding level
   (``floor = 4 eps sqrt(n) max_i L_ii``) on two solves in a row, or has stopped
   improving with ``r <= VEC_TOL * gap``.
4. The shift moves (a new factorization) when the residual falls by less than ten times
   per solve: to ``upper = theta``, or, once ``theta`` no longer moves (lambda3 is
   close), ``rel`` divided by 100. When ``theta`` rises (the iterate turns towards
   lambda3's vector, closer to ``tau``), ``upper`` becomes the smaller Ritz value on
   the span of the last two iterates, which holds most of both vectors, and the
   iterate its Ritz vector.

At most ``MAX_SOLVES`` solves and ``MAX_FACTORIZATIONS`` factorizations (else status
``NO_CONVERGENCE`` or ``INERTIA``).

This module is the numpy implementation; :mod:`tether.graph.small_kernels` compiles the
same arithmetic in the same order (elementwise operations, and sums in numpy's pairwise
order), so both give the same bits and :func:`tether.jit.enabled` changes only the time.
"""

from __future__ import annotations

import math

import numpy as np

#: status codes (0: certified)
OK, BAD_GUESS, TINY, BREAKDOWN, INERTIA, NO_CONVERGENCE = range(6)

#: the solver's settings (see the module docstring)
SHIFT_REL = 1e-4
TINY_REL = 1e-9
TOL_REL = 1e-14
VEC_TOL = 1e-10
MAX_SOLVES = 30
MAX_FACTORIZATIONS = 4
#: largest team (the compiled kernel's sums are numpy's up to this size)
MAX_N = 960
#: the settings in the order the compiled kernels take them
SETTINGS = (SHIFT_REL, TINY_REL, TOL_REL, VEC_TOL, MAX_SOLVES, MAX_FACTORIZATIONS)
#: ``u / (1 - (n + 1) u)``-style constant of the backward-error bound: the unit roundoff
UNIT_ROUNDOFF = 2.0**-53


def center_normalize(x: np.ndarray) -> float:
    """``x <- (x - mean x) / ||x - mean x||`` in place; returns the norm before scaling."""
    x -= np.add.reduce(x) / len(x)
    norm = math.sqrt(np.add.reduce(x * x))
    if norm > 0.0 and math.isfinite(norm):
        x /= norm
    return norm


def rayleigh(lap: np.ndarray, x: np.ndarray) -> tuple[np.ndarray, float, float]:
    """``L x``, the Rayleigh quotient ``x' L x`` of a unit ``x``, ``||L x - theta x||^2``."""
    lx = (lap * x).sum(axis=1)
    theta = float(np.add.reduce(x * lx))
    e = lx - theta * x
    return lx, theta, float(np.add.reduce(e * e))


def ldlt(lap: np.ndarray, tau: float) -> tuple[int, float, np.ndarray, np.ndarray]:
    """``L D L'`` of ``lap - tau I`` without pivoting, ``L'`` above the diagonal of ``f``.

    Returns ``(negative pivots, eta, f, d)`` with ``eta >= ||E||_2`` for the backward
    error ``E`` of the computed factors (Higham's ``gamma_n || |L| |D| |L'| ||_2``, with
    ``gamma`` doubled, bounded by ``|| |L| |D|^(1/2) ||_F^2``); ``negative = -1`` when a
    pivot is zero or not finite. Only ``f``'s upper triangle is meaningful.
    """
    n = len(lap)
    f = lap.copy()
    f[np.diag_indices(n)] -= tau
    d = np.empty(n)
    negative, bound = 0, 0.0
    for k in range(n):
        dk = float(f[k, k])
        if not (dk != 0.0 and math.isfinite(dk)):
            return -1, math.inf, f, d
        d[k] = dk
        negative += dk < 0.0
        inv = 1.0 / dk
        t = f[k, k + 1 :] * inv
        f[k + 1 :, k + 1 :] -= np.outer(t, f[k, k + 1 :])
        f[k, k + 1 :] = t
        bound += abs(dk) * (1.0 + float(np.add.reduce(t * t)))
    if not math.isfinite(bound):
        return -1, math.inf, f, d
    u = UNIT_ROUNDOFF
    gamma = 2.0 * (n + 1) * u / (1.0 - (n + 1) * u)
    return negative, gamma * bound, f, d


def solve(f: np.ndarray, d: np.ndarray, x: np.ndarray) -> None:
    """``x <- (L D L')^{-1} x`` in place with the factors of :func:`ldlt`."""
    n = len(d)
    for k in range(n - 1):
        x[k + 1 :] -= f[k, k + 1 :] * x[k]
    x /= d
    for k in range(n - 1, 0, -1):
        x[:k] -= f[:k, k] * x[k]


def ritz_low(a: float, b: float, c: float, g: float) -> tuple[float, float, float]:
    """Smaller Ritz value and its coefficients on the span of two unit vectors ``p, x``.

    ``a = p'Lp``, ``b = p'Lx``, ``c = x'Lx``, ``g = p'x``: the smaller root ``mu`` of
    ``det([[a, b], [b, c]] - mu [[1, g], [g, 1]]) = 0`` and ``(alpha, beta)`` with
    ``alpha p + beta x`` its Ritz vector; ``mu = inf`` when the two are parallel.
    """
    s = 1.0 - g * g
    if not s > 1e-8:
        return math.inf, 0.0, 1.0
    h = a + c - 2.0 * b * g
    disc = max(h * h - 4.0 * s * (a * c - b * b), 0.0)
    mu = (h - math.sqrt(disc)) / (2.0 * s)
    alpha, beta = b - mu * g, mu - a
    if abs(alpha) + abs(beta) < 1e-300:
        alpha, beta = mu - c, b - mu * g
    return mu, alpha, beta


def small_fiedler(lap: np.ndarray, guess: np.ndarray) -> tuple[int, float, np.ndarray, int, int]:
    """``(status, lambda2, vector, solves, factorizations)`` of the dense Laplacian ``lap``.

    The algorithm of the module docstring from the warm start ``guess``; ``lambda2`` and
    the unit zero-mean ``vector`` (sign not fixed) are certified when ``status == OK``.
    """
    n = len(guess)
    x = np.array(guess, dtype=np.float64)
    if n < 2 or n > MAX_N or lap.shape[0] != n or not center_normalize(x) > 0.0:
        return BAD_GUESS, 0.0, x, 0, 0
    lx, upper, _ = rayleigh(lap, x)
    top = float(np.max(np.diagonal(lap)))
    if not upper > TINY_REL * top:
        return TINY, upper, x, 0, 0
    floor = 4.0 * 2.0**-52 * math.sqrt(n) * top
    f, d = lap, np.ones(n)
    rel = SHIFT_REL
    tau, eta, theta_prev = 0.0, 0.0, upper
    factors, solves, since = 0, 0, 0
    factor, retried = True, False
    last = math.inf
    while solves < MAX_SOLVES:
        if factor:
            if factors == MAX_FACTORIZATIONS:
                return INERTIA, upper, x, solves, factors
            tau = upper * (1.0 + rel)
            negative, eta, f, d = ldlt(lap, tau)
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
            factor, since, last = False, 0, math.inf
        prev = x.copy()
        solve(f, d, x)
        solves += 1
        since += 1
        if not center_normalize(x) > 0.0:
            return BREAKDOWN, upper, x, solves, factors
        lx, theta, res = rayleigh(lap, x)
        r = math.sqrt(res)
        gap = tau - eta - theta
        certified = theta > 0.0 and gap > 0.0 and res <= TOL_REL * theta * gap
        if certified and (
            (r <= floor and last <= floor) or (r >= 0.7 * last and r <= VEC_TOL * gap)
        ):
            return OK, theta, x, solves, factors
        if theta > theta_prev:  # turning towards lambda3: Ritz pair on {prev, x}
            b = float(np.add.reduce(prev * lx))
            g = float(np.add.reduce(prev * x))
            mu, alpha, beta = ritz_low(theta_prev, b, theta, g)
            if mu < upper * (1.0 - rel):
                x = alpha * prev + beta * x
                if not center_normalize(x) > 0.0:
                    return BREAKDOWN, upper, x, solves, factors
                lx, theta, res = rayleigh(lap, x)
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
