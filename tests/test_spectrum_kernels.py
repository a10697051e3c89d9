"""lambda2 without LAPACK (issue 14): Householder + Sturm bisection + Newton, compiled.

:mod:`tether.graph.spectrum_kernels` is another eigensolver than ``numpy.linalg.eigh``
(the reference of :func:`tether.graph.fiedler`), so the values agree to rounding, not bit
for bit: 1e-12 here, on random geometric graphs up to 150 nodes, and against closed
forms (paths, cycles, complete and complete bipartite graphs, stars, hypercubes), which
do not depend on any eigensolver. The tridiagonal reduction must keep every eigenvalue;
the eigenvalue search must find the requested one also among repeated and clustered
eigenvalues and when the tridiagonal splits.
"""

from __future__ import annotations

import itertools
import math

import numpy as np
import pytest

from tether.graph import components, laplacian_dense, pairs_within

pytest.importorskip("numba")

from tether.graph.spectrum_kernels import (  # noqa: E402
    lambda2_kernel,
    tridiagonal_eigenvalue_kernel,
    tridiagonal_kernel,
)


def _geometric(seed: int) -> tuple[int, np.ndarray]:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 150))
    pos = rng.uniform(0.0, 8.0 * math.sqrt(n), (n, 2))
    return n, pairs_within(pos, 15.0).astype(np.int64)


@pytest.mark.parametrize("seed", range(40))
def test_lambda2_matches_eigh(seed: int) -> None:
    n, pairs = _geometric(seed)
    if components(n, pairs)[0] > 1:  # the metrics return 0 there without solving
        pairs = np.concatenate([pairs, [[i, i + 1] for i in range(n - 1)]]).astype(np.int64)
    ref = np.linalg.eigh(laplacian_dense(n, pairs))[0][1]
    assert lambda2_kernel(n, pairs) == pytest.approx(ref, abs=1e-12)


def _closed_forms() -> list[tuple[str, int, np.ndarray, float]]:
    out = []
    for n in (2, 3, 5, 8, 20, 47):
        path = [(i, i + 1) for i in range(n - 1)]
        out.append(("path", n, path, 2.0 - 2.0 * math.cos(math.pi / n)))
        complete = list(itertools.combinations(range(n), 2))
        out.append(("complete", n, complete, float(n)))
        star = [(0, j) for j in range(1, n)]
        out.append(("star", n, star, 1.0 if n > 2 else 2.0))
        if n >= 3:
            cycle = [(i, i + 1) for i in range(n - 1)] + [(0, n - 1)]
            out.append(("cycle", n, cycle, 2.0 - 2.0 * math.cos(2.0 * math.pi / n)))
    for a, b in ((1, 4), (3, 5), (6, 6), (2, 30)):
        bip = [(i, a + j) for i in range(a) for j in range(b)]
        out.append(("bipartite", a + b, bip, float(min(a, b))))
    for d in (2, 3, 5):
        cube = [(v, v ^ (1 << k)) for v in range(2**d) for k in range(d) if v < v ^ (1 << k)]
        out.append(("hypercube", 2**d, cube, 2.0))
    return [(name, n, np.array(p, np.int64).reshape(-1, 2), lam) for name, n, p, lam in out]


@pytest.mark.parametrize(("name", "n", "pairs", "exact"), _closed_forms())
def test_lambda2_closed_forms(name: str, n: int, pairs: np.ndarray, exact: float) -> None:
    """Repeated eigenvalues (cycles, complete graphs, hypercubes) included."""
    rng = np.random.default_rng(n)
    perm = rng.permutation(n)  # labels must not matter
    relabelled = np.sort(perm[pairs], axis=1)
    for p in (pairs, relabelled):
        assert lambda2_kernel(n, p) == pytest.approx(exact, abs=1e-12 * max(1.0, exact)), name


def test_lambda2_of_tiny_graphs() -> None:
    empty = np.empty((0, 2), np.int64)
    assert lambda2_kernel(0, empty) == 0.0
    assert lambda2_kernel(1, empty) == 0.0


@pytest.mark.parametrize("seed", range(10))
def test_tridiagonal_keeps_every_eigenvalue_and_reads_the_lower_triangle(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 40))
    a = rng.normal(size=(n, n))
    a = a + a.T
    a[rng.random((n, n)) < 0.3] = 0.0  # zero columns: reflectors skipped
    a = np.tril(a) + np.tril(a, -1).T
    upper_garbage = a.copy()
    upper_garbage[np.triu_indices(n, 1)] = np.nan
    d, e = tridiagonal_kernel(a.copy())
    d2, e2 = tridiagonal_kernel(upper_garbage)
    np.testing.assert_array_equal(d, d2)
    np.testing.assert_array_equal(e, e2)
    t = np.diag(d) + np.diag(e, 1) + np.diag(e, -1)
    scale = max(1.0, float(np.abs(a).sum(axis=1).max()))
    np.testing.assert_allclose(np.linalg.eigvalsh(t), np.linalg.eigvalsh(a), atol=1e-12 * scale)


@pytest.mark.parametrize("seed", range(12))
def test_every_eigenvalue_of_clustered_and_split_tridiagonals(seed: int) -> None:
    """Each index is found, also where Newton could jump to a neighbour."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 30))
    d = rng.choice([0.0, 1.0, 1.0 + 1e-9, 2.0, 5.0], n) + rng.normal(0.0, 1e-3, n) * (seed % 2)
    e = rng.choice([0.0, 1e-8, 0.5, 1.0], max(n - 1, 0))  # zeros split the matrix
    t = np.diag(d) + np.diag(e, 1) + np.diag(e, -1)
    ref = np.linalg.eigvalsh(t)
    for index in range(n):
        got = tridiagonal_eigenvalue_kernel(d, e, index)
        assert got == pytest.approx(ref[index], abs=1e-12), (index, ref)
