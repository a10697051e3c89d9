from __future__ import annotations

import itertools

import networkx as nx
import numpy as np
import pytest

from tether.graph import (
    algebraic_connectivity,
    components,
    fiedler,
    is_connected,
    laplacian,
    pairs_within,
    stretch,
)


def _random_graph(seed: int, n: int = 25, r: float = 4.0):
    rng = np.random.default_rng(seed)
    pos = rng.uniform(0, 10, (n, 2))
    pairs = pairs_within(pos, r)
    w = rng.uniform(0.1, 3.0, len(pairs))
    g = nx.Graph()
    g.add_nodes_from(range(n))
    g.add_weighted_edges_from(
        (int(a), int(b), float(c)) for (a, b), c in zip(pairs, w, strict=True)
    )
    return pos, pairs, w, g


@pytest.mark.parametrize("seed", range(12))
def test_pairs_within_matches_brute_force(seed):
    rng = np.random.default_rng(seed)
    pos = rng.uniform(0, 10, (60, 3 if seed % 2 else 2))
    got = {tuple(p) for p in pairs_within(pos, 2.5)}
    want = {
        (i, j)
        for i, j in itertools.combinations(range(60), 2)
        if np.linalg.norm(pos[i] - pos[j]) <= 2.5
    }
    assert got == want


@pytest.mark.parametrize("seed", range(12))
def test_lambda2_matches_networkx_weighted(seed):
    _, pairs, w, g = _random_graph(seed)
    if not nx.is_connected(g):
        assert algebraic_connectivity(len(g), pairs, w) == 0.0
        return
    want = nx.algebraic_connectivity(g, weight="weight", method="tracemin_lu", tol=1e-12)
    for method in ("dense", "sparse"):
        assert algebraic_connectivity(len(g), pairs, w, method=method) == pytest.approx(
            want, rel=1e-7, abs=1e-9
        )


@pytest.mark.parametrize("seed", range(6))
def test_fiedler_vector_is_an_eigenvector(seed):
    _, pairs, w, g = _random_graph(seed, r=5.0)
    n = len(g)
    lam, v = fiedler(n, pairs, w, method="sparse")
    lap = laplacian(n, pairs, w).toarray()
    if lam > 0:
        np.testing.assert_allclose(lap @ v, lam * v, atol=1e-8)
        assert abs(v.sum()) < 1e-8


def test_disconnected_graph_has_zero_lambda2_and_components():
    pairs = np.array([[0, 1], [2, 3]])
    assert algebraic_connectivity(4, pairs) == 0.0
    assert algebraic_connectivity(4, pairs, method="sparse") == 0.0
    count, labels = components(4, pairs)
    assert count == 2 and labels[0] == labels[1] != labels[2] == labels[3]
    assert not is_connected(4, pairs)
    assert is_connected(1, np.empty((0, 2), int))


def test_path_graph_lambda2_closed_form():
    # lambda2 of the path P_n is 2 (1 - cos(pi / n))
    n = 9
    pairs = np.array([[i, i + 1] for i in range(n - 1)])
    assert algebraic_connectivity(n, pairs) == pytest.approx(2 * (1 - np.cos(np.pi / n)))


def test_stretch_on_hand_made_graphs():
    square = np.array([[0.0, 0], [1, 0], [1, 1], [0, 1]])
    cycle = np.array([[0, 1], [1, 2], [2, 3], [0, 3]])
    # the diagonal pair goes round two sides: 2 / sqrt(2)
    assert stretch(square, cycle) == pytest.approx(np.sqrt(2))
    complete = np.array(list(itertools.combinations(range(4), 2)))
    assert stretch(square, complete) == pytest.approx(1.0)
    assert stretch(square, cycle[:2]) == float("inf")


@pytest.mark.parametrize("method", ["auto", "dense", "subset", "sparse", "warm"])
def test_disconnected_graph_is_exactly_zero_on_every_solver(method: str) -> None:
    """Two paths of 10 nodes: lambda2 exactly 0 and the component indicator, with or
    without a warm start (one near the indicator, which the warm solver may certify)."""
    pairs = np.array([[i, i + 1] for i in range(9)] + [[i, i + 1] for i in range(10, 19)])
    indicator = np.r_[np.ones(10), -np.ones(10)] / np.sqrt(20)
    rng = np.random.default_rng(0)
    guesses = [indicator + 1e-3 * rng.normal(size=20), rng.normal(size=20)]
    for guess in guesses if method == "warm" else [None, *guesses]:
        lam, vec = fiedler(20, pairs, np.full(18, 0.5), method=method, guess=guess)
        assert lam == 0.0
        assert abs(float(vec @ indicator)) == pytest.approx(1.0, abs=1e-12)
