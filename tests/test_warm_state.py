"""The warm Fiedler solver's kept factorization (:class:`tether.graph.WarmState`).

A kept factorization certifies lambda3 of the *factored* graph; the solver carries the
bound to the current graph by Weyl's inequality with :func:`~tether.graph.links.change_bound`.
These tests check every link of that chain against independent oracles (dense
``eigh``, networkx): the links' arithmetic (kernel = numpy reference, bit for bit), the
bound against the true norm of the change, and the solver on graphs that change step
to step (slowly, abruptly, across an eigenvalue crossing, into and out of
disconnection), with and without the kept factorization.
"""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest
import scipy.linalg

from tether import jit
from tether.graph import WarmState, fiedler, laplacian, laplacian_dense, warm_fiedler
from tether.graph.links import Links, change_bound

pytest.importorskip("numba")


def geometric(seed: int, n: int = 120, r: float = 2.2) -> tuple[np.ndarray, np.ndarray]:
    """Points in a 3 : 2 : 1 box and their links within ``r``."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(0, 1, (n, 3)) * [12.0, 8.0, 4.0]
    return q, _links(q, r)


def _links(q: np.ndarray, r: float) -> np.ndarray:
    d = np.linalg.norm(q[:, None] - q[None], axis=-1)
    i, j = np.nonzero(np.triu(d < r, 1))
    return np.column_stack([i, j])


def _weights(q: np.ndarray, pairs: np.ndarray, r: float) -> np.ndarray:
    """Smooth weights that vanish at ``r`` (links appear and vanish continuously)."""
    d = np.linalg.norm(q[pairs[:, 0]] - q[pairs[:, 1]], axis=1)
    return np.clip(1.0 - (d / r) ** 2, 0.0, None) ** 2


def dense(n: int, pairs: np.ndarray, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return scipy.linalg.eigh(laplacian_dense(n, pairs, w))


# ------------------------------------------------------------------ the links


@pytest.mark.parametrize("seed", range(4))
def test_links_product_and_shifted_matrix(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = 40
    pairs = rng.integers(0, n, (150, 2))  # unordered, repeated, self-loops
    w = rng.uniform(-0.2, 2.0, 150)  # some weights <= 0: dropped
    lap = laplacian(
        n, pairs[(pairs[:, 0] != pairs[:, 1]) & (w > 0)], w[(pairs[:, 0] != pairs[:, 1]) & (w > 0)]
    )
    x = rng.normal(size=n)
    for on in (False, True):
        with jit.using(on):
            g = Links.from_pairs(n, pairs, w)
            assert np.all(g.lo < g.hi) and np.all(np.diff(g.keys) > 0)
            np.testing.assert_allclose(g.product(x), lap @ x, rtol=1e-12, atol=1e-12)
            shifted = g.shifted(0.3)
            assert shifted.has_sorted_indices
            np.testing.assert_allclose(
                shifted.toarray(), lap.toarray() - 0.3 * np.eye(n), rtol=0, atol=1e-12
            )
    with jit.using(False):
        ref = Links.from_pairs(n, pairs, w)
        p_ref, s_ref = ref.product(x), ref.shifted(0.3)
    with jit.using(True):
        got = Links.from_pairs(n, pairs, w)
        p_got, s_got = got.product(x), got.shifted(0.3)
    assert np.array_equal(p_got, p_ref)  # the same arithmetic in the same order
    for a in ("indptr", "indices", "data"):
        assert np.array_equal(getattr(s_got, a), getattr(s_ref, a))


@pytest.mark.parametrize("seed", range(3))
def test_links_of_sorted_pairs_kernel_equals_reference(seed: int) -> None:
    """The compiled fast path for sorted unique pairs (a strategy's) and numpy's."""
    q, pairs = geometric(seed, 80)
    w = _weights(q, pairs, 2.2)
    w[::7] = 0.0  # links of zero weight are dropped
    pairs = np.concatenate([pairs, [[5, 5]]])  # a self-loop too, at the end
    w = np.append(w, 1.0)
    with jit.using(False):
        ref = Links.from_pairs(80, pairs, w)
        ref_deg = ref.degrees
    with jit.using(True):
        got = Links.from_pairs(80, pairs, w)
    for a in ("lo", "hi", "w", "keys"):
        assert np.array_equal(getattr(got, a), getattr(ref, a))
    assert np.array_equal(got.degrees, ref_deg)
    assert np.array_equal(ref_deg, laplacian_dense(80, pairs[:-1], w[:-1]).diagonal()) or (
        np.allclose(ref_deg, laplacian_dense(80, pairs[:-1], w[:-1]).diagonal(), rtol=1e-14)
    )
    assert len(got.w) == int(np.count_nonzero(w[:-1] > 0))


@pytest.mark.parametrize("seed", range(6))
def test_change_bound_bounds_the_true_norm(seed: int) -> None:
    """``||L_b - L_a||_2 <= change_bound`` on graphs that gain and lose links."""
    rng = np.random.default_rng(seed)
    q, _ = geometric(seed, 60)
    qb = q + rng.normal(0, 0.3 if seed % 2 else 0.02, q.shape)
    pa, pb = _links(q, 2.2), _links(qb, 2.2)
    a = Links.from_pairs(60, pa, _weights(q, pa, 2.2))
    b = Links.from_pairs(60, pb, _weights(qb, pb, 2.2))
    diff = laplacian_dense(60, pb, _weights(qb, pb, 2.2)) - laplacian_dense(
        60, pa, _weights(q, pa, 2.2)
    )
    true = float(np.max(np.abs(np.linalg.eigvalsh(diff))))
    with jit.using(False):
        ref = change_bound(a, b)
    with jit.using(True):
        got = change_bound(a, b)
    assert got == ref
    assert true <= got * (1 + 1e-12)
    assert got <= 2 * float(np.max(np.abs(diff).sum(axis=1))) + 1e-12  # not absurdly loose
    assert change_bound(a, a) == 0.0


# ------------------------------------------------------------------ the solver


def _moving_sequence(seed: int, steps: int, sigma: float, n: int = 150):
    """Graphs of a team whose robots move by ``sigma`` per step (links come and go)."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(0, 1, (n, 3)) * [14.0, 7.0, 3.5]
    for _ in range(steps):
        q = q + rng.normal(0, sigma, q.shape)
        pairs = _links(q, 3.0)
        yield pairs, _weights(q, pairs, 3.0)


@pytest.mark.parametrize(("seed", "sigma"), [(0, 1e-4), (1, 1e-3), (2, 0.03), (3, 0.3)])
def test_kept_factorization_on_changing_graphs(seed: int, sigma: float) -> None:
    """Against dense ``eigh`` at every step; slow motion reuses, fast motion refactors."""
    state = WarmState()
    guess = None
    for pairs, w in _moving_sequence(seed, 8, sigma):
        n = 150
        vals, vecs = dense(n, pairs, w)
        if guess is None:
            guess = vecs[:, 1]
        lam, vec = fiedler(n, pairs, w, method="warm", guess=guess, state=state)
        if vals[1] > 1e-9:
            assert lam == pytest.approx(vals[1], rel=1e-9, abs=0)
            if vals[2] - vals[1] > 1e-6 * vals[2]:
                assert abs(float(vec @ vecs[:, 1])) >= 1 - 1e-9
        else:  # a disconnected team: exactly 0 and a component indicator
            assert lam == 0.0
        assert float(vec @ guess) >= 0
        guess = vec
    assert state.factorizations >= 1
    if sigma <= 1e-4:
        assert state.reuses >= 6  # slow motion stays within the certified reach
    elif sigma <= 1e-3:
        assert state.reuses >= 3
    if sigma >= 0.3:
        assert state.reuses == 0  # far beyond it: every step factors afresh


def test_kept_factorization_agrees_with_networkx() -> None:
    """An independent oracle on a weighted geometric graph, after a small move."""
    q, pairs = geometric(11, 130)
    state = WarmState()
    w = _weights(q, pairs, 2.2)
    nu = dense(130, pairs, w)[1][:, 1]
    fiedler(130, pairs, w, method="warm", guess=nu, state=state)
    q = q + np.random.default_rng(1).normal(0, 1e-7, q.shape)
    pairs = _links(q, 2.2)
    w = _weights(q, pairs, 2.2)
    g = nx.Graph()
    g.add_nodes_from(range(130))
    g.add_weighted_edges_from(
        (int(a), int(b), float(c)) for (a, b), c in zip(pairs, w, strict=True)
    )
    if not nx.is_connected(g):
        pytest.skip("this draw is disconnected")
    want = nx.algebraic_connectivity(g, weight="weight", method="tracemin_lu", tol=1e-12)
    reuses = state.reuses
    lam, _ = fiedler(130, pairs, w, method="warm", guess=nu, state=state)
    assert state.reuses == reuses + 1
    assert lam == pytest.approx(want, rel=1e-8)


def _grid(nx_: int, ny: int, a: float, b: float) -> tuple[np.ndarray, np.ndarray]:
    """An ``nx_ x ny`` grid, links of weight ``a`` along x and ``b`` along y."""
    idx = np.arange(nx_ * ny).reshape(nx_, ny)
    along_x = np.column_stack([idx[:-1].ravel(), idx[1:].ravel()])
    along_y = np.column_stack([idx[:, :-1].ravel(), idx[:, 1:].ravel()])
    pairs = np.concatenate([along_x, along_y])
    w = np.concatenate([np.full(len(along_x), a), np.full(len(along_y), b)])
    return pairs, w


def test_eigenvalue_crossing_is_not_certified_as_lambda2() -> None:
    """The old Fiedler vector stays an exact eigenvector but becomes the third one.

    An ``x``-mode and a ``y``-mode of a grid swap order between two calls. The guess
    (the old ``x``-mode) has zero residual on the new graph, so only a correct lower
    bound on lambda3 (the kept one minus the change of the graph) keeps the solver
    from returning lambda3: a solver that forgot the change would return it.
    """
    nx_, ny = 30, 12
    lam_x = 2 * (1 - np.cos(np.pi / nx_))  # weight 1 along x
    b_cross = lam_x / (2 * (1 - np.cos(np.pi / ny)))  # the y weight where they cross
    for b_old, b_new in ((1.02 * b_cross, 0.995 * b_cross), (1.2 * b_cross, 0.9 * b_cross)):
        state = WarmState()
        pairs, w = _grid(nx_, ny, 1.0, b_old)
        vals, vecs = dense(nx_ * ny, pairs, w)
        lam, nu = fiedler(nx_ * ny, pairs, w, method="warm", guess=vecs[:, 1], state=state)
        assert lam == pytest.approx(lam_x, rel=1e-9)
        pairs, w = _grid(nx_, ny, 1.0, b_new)
        vals, _ = dense(nx_ * ny, pairs, w)
        assert vals[1] < lam_x * (1 - 1e-3)  # the y-mode is lambda2 now
        lam, _ = fiedler(nx_ * ny, pairs, w, method="warm", guess=nu, state=state)
        assert lam == pytest.approx(vals[1], rel=1e-9)


def test_disconnection_and_reconnection_with_a_kept_factorization() -> None:
    pairs, w = _grid(20, 10, 1.0, 1.0)
    n = 200
    state = WarmState()
    nu = dense(n, pairs, w)[1][:, 1]
    lam, nu = fiedler(n, pairs, w, method="warm", guess=nu, state=state)
    cut = (pairs // 10)[:, 0] != (pairs // 10)[:, 1]  # links between rows 9 and 10 ...
    middle = cut & ((pairs[:, 0] // 10 == 9) | (pairs[:, 1] // 10 == 9))
    w_cut = np.where(middle & ((pairs // 10).max(axis=1) == 10), 0.0, w)
    lam0, vec0 = fiedler(n, pairs, w_cut, method="warm", guess=nu, state=state)
    assert lam0 == 0.0
    assert abs(float(vec0.sum())) < 1e-9 and float(vec0 @ vec0) == pytest.approx(1.0)
    lam1, _ = fiedler(n, pairs, w, method="warm", guess=vec0, state=state)
    assert lam1 == pytest.approx(lam, rel=1e-9)


def test_fallbacks_when_nothing_can_be_certified() -> None:
    """No certificate -> None from the solver, the exact sparse answer from ``fiedler``."""
    q, pairs = geometric(5, 140)
    w = _weights(q, pairs, 2.2)
    vals, vecs = dense(140, pairs, w)
    state = WarmState()
    assert warm_fiedler(140, pairs, w, np.ones(140), state=state) is None  # no direction
    assert state.factorizations == 0
    # a grid whose lambda3 is 5 % above lambda2: a shift of 100 % reaches past it
    nx_, ny = 30, 12
    pairs, w = _grid(nx_, ny, 1.0, 1.05 * (1 - np.cos(np.pi / nx_)) / (1 - np.cos(np.pi / ny)))
    vals, vecs = dense(nx_ * ny, pairs, w)
    assert warm_fiedler(nx_ * ny, pairs, w, vecs[:, 1], shift_rel=1.0, retries=0) is None
    state = WarmState(shift_rel=1.0)
    assert warm_fiedler(nx_ * ny, pairs, w, vecs[:, 1], state=state, retries=0) is None
    assert state.gap_rel == 1.0  # recorded: the next shifts stay below half of it
    assert state.next_shift(None, 1e-2) == 1e-2
    lam, _ = fiedler(nx_ * ny, pairs, w, method="warm", guess=np.ones(nx_ * ny), state=state)
    assert lam == pytest.approx(vals[1], rel=1e-9)  # sparse Lanczos (fallback)
    lam, _ = warm_fiedler(nx_ * ny, pairs, w, vecs[:, 1], state=state)  # retries reach it
    assert lam == pytest.approx(vals[1], rel=1e-9)


def test_kernels_and_reference_give_the_same_bits() -> None:
    """The whole solver, with and without the compiled kernels, on a changing graph."""
    results = {}
    for on in (False, True):
        with jit.using(on):
            state = WarmState()
            out = []
            guess = None
            for pairs, w in _moving_sequence(4, 5, 1e-3):
                if guess is None:
                    guess = dense(150, pairs, w)[1][:, 1]
                lam, guess = fiedler(150, pairs, w, method="warm", guess=guess, state=state)
                out.append((lam, guess))
            results[on] = (out, state.reuses, state.factorizations)
    assert results[True][1:] == results[False][1:]
    for (la, va), (lb, vb) in zip(results[True][0], results[False][0], strict=True):
        assert la == lb and np.array_equal(va, vb)
