"""The warm-started, certified Fiedler solver against the cold exact one."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

from tether.continuous.connectivity.params import ConnectivityParams
from tether.continuous.connectivity.weights import compute_weights
from tether.graph import SUBSET_MAX_N, warm_fiedler

SPARSE_MIN_N = SUBSET_MAX_N + 1  # the first team size on the sparse / warm solvers

PARAMS = ConnectivityParams()


def free_team(n: int, seed: int) -> np.ndarray:
    """``n`` robots on a jittered, elongated 3-D lattice (spacing 3 m: connected, no contact).

    The box is about 3 : 2 : 1 so that lambda2 and lambda3 are well separated.
    """
    rng = np.random.default_rng(seed)
    nz = max(1, round((n / 6) ** (1 / 3)))
    ny = 2 * nz
    nx = -(-n // (ny * nz))
    cells = np.argwhere(np.ones((nx, ny, nz), dtype=bool))[:n]
    return 3.0 * cells + rng.uniform(-0.4, 0.4, (n, 3))


def dense_pair(graph) -> tuple[float, np.ndarray, np.ndarray]:  # noqa: ANN001
    """Independent oracle: full dense ``eigh`` (lambda2, nu2, nu3)."""
    vals, vecs = scipy.linalg.eigh(graph.laplacian_dense())
    return float(vals[1]), vecs[:, 1], vecs[:, 2]


@pytest.mark.parametrize(("n", "seed"), [(40, 0), (150, 1), (300, 2), (SPARSE_MIN_N + 49, 3)])
def test_warm_equals_cold_on_slowly_moving_team(n: int, seed: int) -> None:
    rng = np.random.default_rng(seed)
    q = free_team(n, seed)
    lam, nu, _ = dense_pair(compute_weights(q, PARAMS))
    certified = 0
    for _ in range(6):
        q = q + rng.normal(0.0, 0.03, q.shape)  # a few integrator steps of motion
        graph = compute_weights(q, PARAMS)
        lam, exact, _ = dense_pair(graph)
        warm = warm_fiedler(graph.n, graph.pairs, graph.weights, nu)
        if warm is not None:
            certified += 1
            assert warm[0] == pytest.approx(lam, rel=1e-9, abs=0)
            assert abs(float(warm[1] @ exact)) == pytest.approx(1.0, abs=1e-8)
            assert float(warm[1] @ nu) > 0  # sign follows the guess
        got = graph.fiedler(guess=nu)  # warm above SPARSE_MIN_N, dense below
        assert got[0] == pytest.approx(lam, rel=1e-9, abs=0)
        nu = got[1]
    assert certified == 6  # a good warm start is always certified on these teams


def test_wrong_guess_is_rejected_not_returned() -> None:
    """Warm-started from the third eigenvector, the solver must not return lambda3."""
    q = free_team(SPARSE_MIN_N + 9, 7)
    graph = compute_weights(q, PARAMS)
    lam, _, nu3 = dense_pair(graph)
    warm = warm_fiedler(graph.n, graph.pairs, graph.weights, nu3)
    if warm is not None:  # allowed only if it still found lambda2 (certified)
        assert warm[0] == pytest.approx(lam, rel=1e-9, abs=0)
    assert graph.fiedler(guess=nu3)[0] == pytest.approx(lam, rel=1e-9, abs=0)


def test_disconnected_team_falls_back() -> None:
    q = np.concatenate([free_team(SPARSE_MIN_N, 4), free_team(20, 5) + [0.0, 0.0, 500.0]])
    graph = compute_weights(q, PARAMS)
    assert (
        warm_fiedler(
            graph.n, graph.pairs, graph.weights, np.random.default_rng(0).normal(size=len(q))
        )
        is None
    )
    assert graph.fiedler(guess=np.ones(len(q)))[0] == pytest.approx(0.0, abs=1e-9)
