"""lambda2 of a small unweighted graph without ``numpy.linalg.eigh`` (numba).

The algebraic connectivity (Fiedler 1973) is the second-smallest eigenvalue of the
Laplacian ``L = D - A``. :func:`tether.graph.fiedler.fiedler` gets it, with the Fiedler
vector, from LAPACK (``eigh`` of the dense Laplacian); the team metrics recorded every
step need the value only, and for a 20-robot team LAPACK's call and workspace cost more
than the arithmetic. Here, in one compiled call:

* Householder reduction of the dense Laplacian to a symmetric tridiagonal ``T``
  (Golub and Van Loan, *Matrix Computations*, 4th ed., Alg. 8.3.1; LAPACK ``dsytd2``'s
  reflectors), ``4 n^3 / 3`` flops, no vectors accumulated;
* the second eigenvalue of ``T`` by bisection on Sturm counts (Golub and Van Loan,
  Sec. 8.4.1; LAPACK ``dstebz``'s negcount with its pivot guard) until it is alone in
  the bracket, then safeguarded Newton steps on the characteristic polynomial (its
  logarithmic derivative from the same pivots), to an absolute ``eps * ||T||``.

Both steps are backward stable, so the value agrees with ``eigh``'s to rounding
(``O(n eps ||L||)``), not bit for bit (tests: 1e-12 against ``numpy.linalg.eigh`` on
random graphs, and closed forms: paths, cycles, complete graphs, stars, hypercubes).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tether.graph.kernels import laplacian_dense_kernel

EPS = 2.220446049250313e-16  # machine epsilon of float64 (numpy.finfo(float).eps)
SAFE_MIN = 2.2250738585072014e-308  # smallest normal float64


@njit(cache=True)
def tridiagonal_kernel(a):  # noqa: ANN001, ANN201
    """Diagonal ``d`` (n) and off-diagonal ``e`` (n - 1) of ``Q^T A Q`` (Householder).

    ``a`` (symmetric, ``(n, n)``; its lower triangle is read) is overwritten. Column
    ``k``'s reflector maps ``a[k+1:, k]`` to ``beta e_1`` with
    ``|beta| = ||a[k+1:, k]||``.
    """
    n = a.shape[0]
    d = np.empty(n)
    e = np.zeros(max(n - 1, 0))
    v = np.empty(n)
    w = np.empty(n)
    for k in range(n - 2):
        x0 = a[k + 1, k]
        tail = 0.0
        for i in range(k + 2, n):
            tail += a[i, k] * a[i, k]
        if tail == 0.0:  # already tridiagonal in this column
            e[k] = x0
            continue
        beta = -math.copysign(math.sqrt(x0 * x0 + tail), x0)
        tau = (beta - x0) / beta
        scale = 1.0 / (x0 - beta)
        v[k + 1] = 1.0
        for i in range(k + 2, n):
            v[i] = a[i, k] * scale
        # A22 <- H A22 H with H = I - tau v v^T, on the lower triangle only:
        # w = tau A22 v, w -= (tau/2)(w.v) v, A22 -= v w^T + w v^T
        for i in range(k + 1, n):
            w[i] = 0.0
        for i in range(k + 1, n):
            vi = tau * v[i]
            s = 0.0
            for j in range(k + 1, i):  # a[i, j] = a[j, i] below the diagonal
                w[j] += a[i, j] * vi
                s += a[i, j] * v[j]
            w[i] += tau * (s + a[i, i] * v[i])
        vw = 0.0
        for i in range(k + 1, n):
            vw += w[i] * v[i]
        alpha = -0.5 * tau * vw
        for i in range(k + 1, n):
            w[i] += alpha * v[i]
        for i in range(k + 1, n):
            vi, wi = v[i], w[i]
            for j in range(k + 1, i + 1):
                a[i, j] -= vi * w[j] + wi * v[j]
        e[k] = beta
    for k in range(n):
        d[k] = a[k, k]
    if n >= 2:
        e[n - 2] = a[n - 1, n - 2]
    return d, e


@njit(cache=True)
def _count_below(d, e2, x, pivmin):  # noqa: ANN001, ANN202
    """Eigenvalues of ``T`` at most ``x`` (Sturm count, ``dstebz``'s pivot guard)."""
    count = 0
    q = d[0] - x
    if abs(q) < pivmin:
        q = -pivmin
    if q <= 0.0:
        count += 1
    for i in range(1, len(d)):
        q = d[i] - e2[i - 1] / q - x
        if abs(q) < pivmin:
            q = -pivmin
        if q <= 0.0:
            count += 1
    return count


@njit(cache=True)
def _newton_pass(d, e2, x, pivmin):  # noqa: ANN001, ANN202
    """:func:`_count_below` at ``x`` and ``S = d/dx log|det(T - x I)|``.

    The pivots ``q_i`` of ``T - x I = L D L^T`` are those of the count; ``S`` sums
    ``q_i' / q_i`` with ``q_i' = -1 + (e_{i-1}^2 / q_{i-1}) (q_{i-1}' / q_{i-1})``, so
    ``x - 1 / S`` is Newton's step on the characteristic polynomial.
    """
    q = d[0] - x
    if abs(q) < pivmin:
        q = -pivmin
    count = 1 if q <= 0.0 else 0
    g = -1.0 / q
    s = g
    for i in range(1, len(d)):
        t = e2[i - 1] / q
        q = d[i] - t - x
        if abs(q) < pivmin:
            q = -pivmin
        if q <= 0.0:
            count += 1
        g = (t * g - 1.0) / q
        s += g
    return count, s


@njit(cache=True)
def tridiagonal_eigenvalue_kernel(d, e, index):  # noqa: ANN001, ANN201
    """The ``index``-th smallest eigenvalue (0-based) of the tridiagonal ``(d, e)``.

    Bisection on Sturm counts keeps a bracket ``[lo, hi]`` with
    ``count(lo) <= index < count(hi)``. Once the bracket holds that eigenvalue alone,
    Newton steps on the characteristic polynomial (:func:`_newton_pass`, each also a
    Sturm count that shrinks the bracket) replace the halvings; a step leaving the
    bracket is replaced by a halving, and a converged step (below ``eps ||T||``) is
    accepted only if the counts at ``+-2 eps ||T||`` around it bracket the eigenvalue.
    Bisection alone needs ~55 passes to ``eps ||T||``; with a multiple eigenvalue the
    bracket never isolates it and plain bisection finishes.
    """
    n = len(d)
    e2 = np.empty(max(n - 1, 0))
    lo, hi, big = np.inf, -np.inf, 1.0
    for i in range(n):  # Gershgorin discs hold every eigenvalue
        r = (abs(e[i - 1]) if i > 0 else 0.0) + (abs(e[i]) if i < n - 1 else 0.0)
        lo = min(lo, d[i] - r)
        hi = max(hi, d[i] + r)
    for i in range(n - 1):
        e2[i] = e[i] * e[i]
        big = max(big, e2[i])
    pivmin = SAFE_MIN * big
    norm = max(abs(lo), abs(hi))
    lo -= 2.0 * EPS * norm + pivmin
    hi += 2.0 * EPS * norm + pivmin
    atol = EPS * norm
    count_lo, count_hi = 0, n
    newton = False
    x = 0.5 * (lo + hi)
    for _ in range(300):  # bisection alone needs ~60 passes from a bracket of ||T||
        if hi - lo <= atol:
            break
        if not newton and count_lo == index and count_hi == index + 1:
            newton = True  # isolated: Newton from the bracket's middle
            x = 0.5 * (lo + hi)
        if not newton:
            mid = 0.5 * (lo + hi)
            if mid <= lo or mid >= hi:
                break
            c = _count_below(d, e2, mid, pivmin)
            if c > index:
                hi, count_hi = mid, c
            else:
                lo, count_lo = mid, c
            continue
        c, s = _newton_pass(d, e2, x, pivmin)
        if c > index:
            hi = x
        else:
            lo = x
        if s == 0.0 or not math.isfinite(s):
            x = 0.5 * (lo + hi)
            continue
        nxt = x - 1.0 / s
        if abs(nxt - x) <= atol:
            below = _count_below(d, e2, nxt - 2.0 * atol, pivmin)
            if below <= index < _count_below(d, e2, nxt + 2.0 * atol, pivmin):
                return nxt
        x = nxt if lo < nxt < hi else 0.5 * (lo + hi)
    return 0.5 * (lo + hi)


@njit(cache=True)
def lambda2_kernel(n, pairs):  # noqa: ANN001, ANN201
    """lambda2 of the unweighted graph (``n`` nodes, ``(m, 2)`` int64 links), ``>= 0``.

    The caller handles disconnected graphs (lambda2 is exactly 0 there: the metrics
    take it from the component count, as :func:`~tether.graph.fiedler.fiedler` does).
    """
    if n < 2:
        return 0.0
    lap = laplacian_dense_kernel(n, pairs, np.ones(len(pairs)))
    d, e = tridiagonal_kernel(lap)
    return max(tridiagonal_eigenvalue_kernel(d, e, 1), 0.0)


def warm_up() -> None:
    """Compile (or load from numba's cache) the kernels."""
    lambda2_kernel(3, np.array([[0, 1], [1, 2]], np.int64))
