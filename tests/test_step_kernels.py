"""The compiled eigenpair of one sub-step (``tether.continuous.connectivity.kernels``) and the
compiled ``dsyevr`` call (``tether.graph.lapack_kernels``) give the reference's bits.

Oracles: scipy's f2py ``dsyevr`` wrapper (the reference's call), the numpy path of
``tether.graph.fiedler.fiedler`` (``TETHER_JIT=off``) and networkx's algebraic
connectivity (an independent solver, to a tolerance)."""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest
import scipy.linalg.lapack

from tether import jit
from tether.graph import fiedler, laplacian_dense, small
from tether.graph.fiedler import _syevr_lwork

pytestmark = pytest.mark.skipif(not jit.available(), reason="needs numba")


def _graph(rng: np.random.Generator, n: int, density: float) -> tuple[np.ndarray, np.ndarray]:
    """A random weighted graph with a path through all nodes (connected) and some zeros."""
    pairs = [(i, i + 1) for i in range(n - 1)]
    pairs += [(i, j) for i in range(n) for j in range(i + 2, n) if rng.random() < density]
    w = rng.random(len(pairs)) * (rng.random(len(pairs)) < 0.9)
    w[: n - 1] = 0.05 + rng.random(n - 1)  # the path keeps it connected
    return np.array(pairs, dtype=np.int64), w


@pytest.mark.parametrize("seed", range(6))
def test_compiled_dsyevr_is_the_f2py_call(seed: int) -> None:
    """Same routine, arguments and workspace: same bits (a wrong ``uplo``, ``abstol``,
    ``il``/``iu`` or workspace size changes them)."""
    from tether.graph.lapack_kernels import syevr_second_kernel

    rng = np.random.default_rng(seed)
    for n in (3, 17, 35, 60, 120):
        pairs, w = _graph(rng, n, 0.2)
        lap = laplacian_dense(n, pairs, w)
        lw, liw = _syevr_lwork(n)
        vals, vecs, m, _, info = scipy.linalg.lapack.dsyevr(
            lap, compute_v=1, range="I", il=2, iu=2, lower=1, lwork=lw, liwork=liw
        )
        val, vec, found, status = syevr_second_kernel(lap, lw, liw)
        assert (found, status) == (m, info) == (1, 0)
        assert val == vals[0] and np.array_equal(vec, vecs[:, 0])
        g = nx.Graph()
        g.add_weighted_edges_from((int(i), int(j), x) for (i, j), x in zip(pairs, w, strict=True))
        assert val == pytest.approx(nx.algebraic_connectivity(g, method="tracemin_lu",
                                                               tol=1e-12), rel=1e-6)  # fmt: skip


@pytest.mark.parametrize("method", ["auto", "lapack"])
@pytest.mark.parametrize("seed", range(4))
def test_fiedler_kernel_is_fiedler(method: str, seed: int) -> None:
    """Decided pairs equal ``fiedler``'s numpy path bit for bit, the sign follows the
    guess, and a connected graph is always decided (the kernel does not just punt)."""
    from tether.continuous.connectivity.kernels import fiedler_kernel

    rng = np.random.default_rng(seed)
    for n in (2, 5, 16, 17, 35, 80):  # up to 16 the full eigh, then the subset solvers
        pairs, w = _graph(rng, n, 0.15)
        lap = laplacian_dense(n, pairs, w)
        _, exact = fiedler(n, pairs, w, method="lapack")
        for flip in (1.0, -1.0):
            guess = flip * (exact + rng.normal(0.0, 0.05, n))
            with jit.using(False):
                lam, vec = fiedler(n, pairs, w, guess=guess, method=method, laplacian=lap)
            decided, k_lam, k_vec, _ = fiedler_kernel(
                lap, len(pairs), guess, method == "lapack", small.SETTINGS, *_syevr_lwork(n)
            )
            assert decided
            assert k_lam == lam and np.array_equal(k_vec, vec)
            assert float(k_vec @ guess) > 0


def test_small_solver_failure_falls_back_to_dsyevr_in_the_kernel() -> None:
    """A cycle has lambda2 = lambda3: the small solver cannot certify, the kernel's
    dsyevr answer is the reference's (which also falls back)."""
    from tether.continuous.connectivity.kernels import fiedler_kernel

    n = 36
    pairs = np.array([(i, (i + 1) % n) for i in range(n)], dtype=np.int64)
    pairs = np.sort(pairs, axis=1)
    w = np.ones(n)
    lap = laplacian_dense(n, pairs, w)
    guess = np.cos(2 * np.pi * np.arange(n) / n) + 0.01 * np.sin(np.arange(n))
    with jit.using(False):
        lam, vec = fiedler(n, pairs, w, guess=guess, method="auto", laplacian=lap)
    decided, k_lam, k_vec, status = fiedler_kernel(lap, n, guess, False, small.SETTINGS,
                                                   *_syevr_lwork(n))  # fmt: skip
    assert status != small.OK and decided
    assert k_lam == lam and np.array_equal(k_vec, vec)
    assert lam == pytest.approx(2.0 - 2.0 * np.cos(2 * np.pi / n), rel=1e-12)


@pytest.mark.parametrize("n", [10, 30])
@pytest.mark.parametrize("method", ["auto", "lapack"])
def test_disconnected_graph_is_left_to_fiedler(method: str, n: int) -> None:
    """lambda2 at rounding level: the kernel does not decide; ``fiedler`` gives exactly 0
    and a component vector (what a kernel returning eigh's or dsyevr's tiny value would
    miss)."""
    from tether.continuous.connectivity.kernels import fiedler_kernel

    rng = np.random.default_rng(5)
    pairs, w = _graph(rng, n, 0.2)
    cut = (pairs[:, 0] < n // 3) != (pairs[:, 1] < n // 3)
    w[cut] = 0.0
    lap = laplacian_dense(n, pairs, w)
    guess = np.where(np.arange(n) < n // 3, 1.0, -0.5) + rng.normal(0, 0.01, n)
    decided, *_ = fiedler_kernel(lap, len(pairs), guess, method == "lapack", small.SETTINGS,
                                 *_syevr_lwork(n))  # fmt: skip
    assert not decided
    lam, vec = fiedler(n, pairs, w, guess=guess, method=method)
    assert lam == 0.0 and len(np.unique(np.round(vec, 12))) == 2
