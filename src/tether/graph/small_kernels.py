"""Compiled kernel of :mod:`tether.graph.small` (numba; imported only when kernels run).

:func:`small_fiedler_kernel` is :func:`tether.graph.small.small_fiedler` with every
operation in the same order: elementwise updates as numpy's, and every sum in numpy's
pairwise order (:func:`tether.graph.kernels.pairwise_sum`), so both give the same bits
(``tests/test_small_fiedler.py``). Inner loops run over unsigned offsets or slices so
that they vectorise.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, uint64

from tether.graph.kernels import block_sum
from tether.graph.small import (
    BAD_GUESS,
    BREAKDOWN,
    INERTIA,
    MAX_FACTORIZATIONS,
    MAX_N,
    MAX_SOLVES,
    NO_CONVERGENCE,
    OK,
    SHIFT_REL,
    TINY,
    TINY_REL,
    TOL_REL,
    UNIT_ROUNDOFF,
    VEC_TOL,
)


@njit(cache=True)
def pairwise_sum(a, lo, n):  # noqa: ANN001, ANN201
    """``numpy.add.reduce(a[lo:lo + n])`` (contiguous) in numpy's order, without recursion.

    numpy halves a run longer than 128 (the first half rounded down to a multiple of 8)
    and adds the two halves' sums; here the halving is unrolled three levels deep, which
    is exact for ``n <= MAX_N`` (969 and beyond need a fourth;
    :func:`tether.graph.kernels.pairwise_sum` is the recursive form, but numba cannot
    load a recursive function compiled into another module from its cache).
    """
    if n <= 128:
        return block_sum(a, lo, n)
    h = n // 2
    h -= h % 8
    halves = 0.0
    for side in range(2):
        lo1, n1 = (lo, h) if side == 0 else (lo + h, n - h)
        if n1 <= 128:
            part = block_sum(a, lo1, n1)
        else:
            h1 = n1 // 2
            h1 -= h1 % 8
            part = 0.0
            for side1 in range(2):
                lo2, n2 = (lo1, h1) if side1 == 0 else (lo1 + h1, n1 - h1)
                if n2 <= 128:
                    q = block_sum(a, lo2, n2)
                else:
                    h2 = n2 // 2
                    h2 -= h2 % 8
                    q = block_sum(a, lo2, h2) + block_sum(a, lo2 + h2, n2 - h2)
                part = q if side1 == 0 else part + q
        halves = part if side == 0 else halves + part
    return halves


@njit(cache=True)
def _sum(a):  # noqa: ANN001, ANN202
    """``numpy.add.reduce(a)`` of a contiguous vector, in numpy's (pairwise) order."""
    return pairwise_sum(a, 0, len(a))


@njit(cache=True)
def _rayleigh(lap, x, lx, tmp):  # noqa: ANN001, ANN202
    """``lx = lap @ x`` (``(lap * x).sum(axis=1)``), the Rayleigh quotient ``theta = x' L x``
    of a unit ``x`` and the residual's squared norm ``||L x - theta x||^2``."""
    n = len(x)
    for i in range(n):
        row = lap[i]
        for j in range(n):
            tmp[j] = row[j] * x[j]
        lx[i] = _sum(tmp)
    for i in range(n):
        tmp[i] = x[i] * lx[i]
    theta = _sum(tmp)
    for i in range(n):
        e = lx[i] - theta * x[i]
        tmp[i] = e * e
    return theta, _sum(tmp)


@njit(cache=True)
def _ldlt(lap, tau, f, d, tmp):  # noqa: ANN001, ANN202
    """``L D L'`` of ``lap - tau I`` without pivoting: ``L'`` above ``f``'s diagonal, ``L`` below.

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
        m = n - 1 - k
        for i in range(k + 1, n):  # Schur complement, upper triangle, row by row
            t = f[k, i] * inv
            a, b = uint64(i * n + i), uint64(k * n + i)
            for j in range(uint64(n - i)):
                flat[a + j] -= t * flat[b + j]
        for i in range(k + 1, n):
            lik = f[k, i] * inv
            f[k, i] = lik
            f[i, k] = lik
            tmp[i - k - 1] = lik * lik
        bound += abs(dk) * (1.0 + pairwise_sum(tmp, 0, m))
    if not math.isfinite(bound):
        return -1, np.inf
    u = UNIT_ROUNDOFF
    gamma = 2.0 * (n + 1) * u / (1.0 - (n + 1) * u)
    return negative, gamma * bound


@njit(cache=True)
def _solve(f, d, x):  # noqa: ANN001, ANN202
    """``x <- (L D L')^{-1} x`` with the factors of :func:`_ldlt` (column-oriented sweeps)."""
    n = len(d)
    for k in range(n - 1):  # L z = x: column k of L is row k of L'
        xk = x[k]
        a = x[k + 1 :]
        b = f[k, k + 1 :]
        for i in range(n - 1 - k):
            a[i] -= b[i] * xk
    for k in range(n):
        x[k] /= d[k]
    for k in range(n - 1, 0, -1):  # L' y = z: column k of L' is row k of L
        xk = x[k]
        a = x[:k]
        b = f[k, :k]
        for i in range(k):
            a[i] -= b[i] * xk


@njit(cache=True)
def _center_normalize(x, tmp):  # noqa: ANN001, ANN202
    """``x <- (x - mean x) / ||x - mean x||``; returns the norm before scaling."""
    n = len(x)
    mean = _sum(x) / n
    for i in range(n):
        x[i] -= mean
        tmp[i] = x[i] * x[i]
    norm = math.sqrt(_sum(tmp))
    if norm > 0.0 and math.isfinite(norm):
        for i in range(n):
            x[i] /= norm
    return norm


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
    """:func:`tether.graph.small.small_fiedler` with its settings as arguments.

    Returns ``(status, lambda2, vector, solves, factorizations)``.
    """
    n = len(guess)
    x = guess.astype(np.float64)
    tmp = np.empty(n)
    if n < 2 or n > MAX_N or lap.shape[0] != n or not _center_normalize(x, tmp) > 0.0:
        return BAD_GUESS, 0.0, x, 0, 0
    lx = np.empty(n)
    upper, _ = _rayleigh(lap, x, lx, tmp)
    top = lap[0, 0]
    for i in range(1, n):
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
            negative, eta = _ldlt(lap, tau, f, d, tmp)
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
        if not _center_normalize(x, tmp) > 0.0:
            return BREAKDOWN, upper, x, solves, factors
        theta, res = _rayleigh(lap, x, lx, tmp)
        r = math.sqrt(res)
        gap = tau - eta - theta
        certified = theta > 0.0 and gap > 0.0 and res <= tol_rel * theta * gap
        if certified and (
            (r <= floor and last <= floor) or (r >= 0.7 * last and r <= vec_tol * gap)
        ):
            return OK, theta, x, solves, factors
        if theta > theta_prev:  # turning towards lambda3: Ritz pair on {prev, x}
            for i in range(n):
                tmp[i] = prev[i] * lx[i]
            b = _sum(tmp)
            for i in range(n):
                tmp[i] = prev[i] * x[i]
            g = _sum(tmp)
            mu, alpha, beta = _ritz_low(theta_prev, b, theta, g)
            if mu < upper * (1.0 - rel):
                for i in range(n):
                    x[i] = alpha * prev[i] + beta * x[i]  # numpy: alpha * prev + beta * x
                if not _center_normalize(x, tmp) > 0.0:
                    return BREAKDOWN, upper, x, solves, factors
                theta, res = _rayleigh(lap, x, lx, tmp)
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
    small_fiedler_kernel(
        lap, np.array([-1.0, 0.1, 1.0]), SHIFT_REL, TINY_REL, TOL_REL, VEC_TOL, MAX_SOLVES,
        MAX_FACTORIZATIONS,
    )  # fmt: skip
