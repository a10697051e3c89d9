"""The certified small dense Fiedler solver against LAPACK, numpy and networkx.

Oracles: ``dsyevr`` (``fiedler(method="subset")``), ``numpy.linalg.eigh`` and
``networkx.algebraic_connectivity``; the compiled kernel against the numpy solver bit
for bit; the certificate's failure paths (a guess at lambda3's vector, equal lambda2
and lambda3, a disconnected graph) end in the LAPACK answer.
"""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest

from tether import jit
from tether.graph import fiedler, laplacian_dense, small
from tether.graph.fiedler import _subset

pytestmark = pytest.mark.skipif(not jit.available(), reason="needs numba")


def random_graph(rng: np.random.Generator, n: int) -> tuple[np.ndarray, np.ndarray]:
    """A random weighted graph (weights in (0, 1]); connected or not."""
    p = rng.uniform(0.08, 0.6)
    pairs = np.argwhere(np.triu(rng.random((n, n)) < p, 1))
    return pairs, rng.uniform(1e-3, 1.0, len(pairs))


def guess_near(vec: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    return vec + rng.normal(0.0, 10 ** rng.uniform(-7, -1), len(vec))


def kernel(lap: np.ndarray, guess: np.ndarray) -> tuple:
    from tether.graph.small_kernels import small_fiedler_kernel

    return small_fiedler_kernel(
        lap, guess, small.SHIFT_REL, small.TINY_REL, small.TOL_REL, small.VEC_TOL,
        small.MAX_SOLVES, small.MAX_FACTORIZATIONS,
    )  # fmt: skip


def test_certified_pairs_agree_with_dsyevr_eigh_and_networkx() -> None:
    """Fails if the certificate accepts a wrong eigenpair or stops too early."""
    rng = np.random.default_rng(14)
    certified = 0
    for _ in range(400):
        n = int(rng.integers(17, 60))
        pairs, w = random_graph(rng, n)
        lap = laplacian_dense(n, pairs, w)
        vals, vecs = np.linalg.eigh(lap)
        scale = float(np.max(np.diagonal(lap)))
        status, lam, vec, _, _ = small.small_fiedler(lap, guess_near(vecs[:, 1], rng))
        if status != small.OK:
            continue
        certified += 1
        ref_lam, ref_vec = _subset(n, pairs, w, lap)
        assert abs(lam - ref_lam) <= 1e-14 * scale
        assert abs(lam - vals[1]) <= 1e-14 * scale
        assert abs(float(vec.sum())) < 1e-12 and abs(float(vec @ vec) - 1.0) < 1e-14
        if vals[1] > 1e-9 * scale and certified % 10 == 1:  # networkx on every tenth
            g = nx.Graph()
            g.add_nodes_from(range(n))
            g.add_weighted_edges_from(
                (int(a), int(b), float(x)) for (a, b), x in zip(pairs, w, strict=True)
            )
            nx_lam = nx.algebraic_connectivity(g, tol=1e-12, method="tracemin_lu")
            assert lam == pytest.approx(nx_lam, rel=1e-8)
        if vals[1] > 1e-9 * scale:  # connected: the vector is unique up to its sign
            ref_vec = ref_vec * np.sign(float(ref_vec @ vec))
            # Davis-Kahan: both within (rounding / gap) of the true vector
            gap = (vals[2] - vals[1]) / scale
            diff = float(np.max(np.abs(vec - ref_vec)))
            assert diff <= 1e-12 / gap
    assert certified >= 300  # good guesses are certified almost always


@pytest.mark.parametrize("seed", range(2))
def test_kernel_is_bit_identical_to_numpy(seed: int) -> None:
    """Every status path (certified, tiny, inertia, ...) gives the same bits compiled."""
    rng = np.random.default_rng(seed)
    statuses = set()
    for _ in range(150):
        n = int(rng.integers(3, 70))
        pairs, w = random_graph(rng, n)
        lap = laplacian_dense(n, pairs, w)
        vecs = np.linalg.eigh(lap)[1]
        guess = guess_near(vecs[:, 1 + int(rng.integers(0, 3) == 0)], rng)  # some at lambda3
        a = kernel(lap, guess)
        b = small.small_fiedler(lap, guess)
        statuses.add(b[0])
        assert a[0] == b[0] and a[1] == b[1] and a[3:] == b[3:]
        assert np.array_equal(a[2], b[2])
    assert {small.OK, small.INERTIA} <= statuses


def test_pairwise_sum_is_numpys_for_every_length() -> None:
    from tether.graph.small_kernels import pairwise_sum

    rng = np.random.default_rng(1)
    for n in range(small.MAX_N + 1):
        a = rng.normal(size=n) * 10.0 ** rng.uniform(-6, 6, n)
        assert pairwise_sum(a, 0, n) == np.add.reduce(a), n


def test_guess_at_lambda3_is_rejected_or_still_lambda2() -> None:
    """Warm-started from the third eigenvector the solver must not return lambda3."""
    rng = np.random.default_rng(3)
    rejected = 0
    for _ in range(60):
        n = int(rng.integers(17, 50))
        pairs, w = random_graph(rng, n)
        lap = laplacian_dense(n, pairs, w)
        vals, vecs = np.linalg.eigh(lap)
        if vals[1] < 1e-6 or vals[2] - vals[1] < 1e-6 * vals[2]:
            continue
        status, lam, _, _, _ = small.small_fiedler(lap, vecs[:, 2])
        if status == small.OK:
            assert lam == pytest.approx(vals[1], rel=1e-12)
        else:
            rejected += 1
        assert fiedler(n, pairs, w, guess=vecs[:, 2])[0] == pytest.approx(vals[1], rel=1e-12)
    assert rejected > 0  # the failure path is exercised


def test_equal_lambda2_and_lambda3_fall_back_to_dsyevr() -> None:
    """A cycle has lambda2 = lambda3: no certificate, the LAPACK answer is returned."""
    n = 24
    pairs = np.array([(i, (i + 1) % n) for i in range(n)])
    pairs.sort(axis=1)
    w = np.ones(n)
    lap = laplacian_dense(n, pairs, w)
    vals = np.linalg.eigvalsh(lap)
    assert vals[2] - vals[1] < 1e-12
    guess = np.cos(2 * np.pi * np.arange(n) / n) + 0.01 * np.sin(2 * np.pi * np.arange(n) / n)
    assert small.small_fiedler(lap, guess)[0] != small.OK
    lam, vec = fiedler(n, pairs, w, guess=guess)
    ref_lam, ref_vec = fiedler(n, pairs, w, guess=guess, method="subset")
    assert lam == ref_lam and np.array_equal(vec, ref_vec)  # the fallback, bit for bit


def test_disconnected_graph_gives_zero_and_a_component_vector() -> None:
    rng = np.random.default_rng(5)
    n = 30
    a = np.argwhere(np.triu(rng.random((15, 15)) < 0.5, 1))
    pairs = np.concatenate([a, a + 15])
    w = rng.uniform(0.1, 1.0, len(pairs))
    guess = np.r_[np.ones(15), -np.ones(15)] + rng.normal(0, 0.1, n)
    lam, vec = fiedler(n, pairs, w, guess=guess)
    ref = fiedler(n, pairs, w, guess=guess, method="lapack")
    assert lam == 0.0 == ref[0] and np.array_equal(vec, ref[1])
    assert float(vec @ guess) > 0


def test_sign_follows_the_guess_as_with_the_reference() -> None:
    rng = np.random.default_rng(6)
    n = 40
    pairs, w = random_graph(rng, n)
    pairs = np.concatenate([pairs, np.c_[np.arange(n - 1), np.arange(1, n)]])  # connected
    pairs = np.unique(pairs, axis=0)
    w = rng.uniform(0.1, 1.0, len(pairs))
    ref_lam, ref_vec = fiedler(n, pairs, w, method="subset")
    for sign in (1.0, -1.0):
        guess = sign * ref_vec + rng.normal(0, 1e-3, n)
        lam, vec = fiedler(n, pairs, w, guess=guess, method="small")
        ref = fiedler(n, pairs, w, guess=guess, method="subset")
        assert float(vec @ guess) > 0 and float(ref[1] @ guess) > 0
        assert lam == pytest.approx(ref[0], rel=1e-13)
        assert np.max(np.abs(vec - ref[1])) < 1e-10


def test_auto_uses_small_only_with_a_guess_and_from_17_nodes() -> None:
    rng = np.random.default_rng(7)
    for n in (10, 16, 17, 40):
        pairs = np.c_[np.arange(n - 1), np.arange(1, n)]
        w = rng.uniform(0.5, 1.0, n - 1)
        guess = fiedler(n, pairs, w, method="dense")[1]
        got = fiedler(n, pairs, w, guess=guess)
        lapack = fiedler(n, pairs, w, guess=guess, method="lapack")
        small_ = fiedler(n, pairs, w, guess=guess, method="small")
        expect = lapack if n <= 16 else small_
        assert got[0] == expect[0] and np.array_equal(got[1], expect[1])
        assert fiedler(n, pairs, w)[0] == fiedler(n, pairs, w, method="lapack")[0]
    with pytest.raises(ValueError, match="needs a guess"):
        fiedler(20, np.c_[np.arange(19), np.arange(1, 20)], method="small")


def test_compiled_and_numpy_paths_of_fiedler_agree_bitwise() -> None:
    rng = np.random.default_rng(8)
    n = 35
    pairs, w = random_graph(rng, n)
    lap = laplacian_dense(n, pairs, w)
    guess = guess_near(np.linalg.eigh(lap)[1][:, 1], rng)
    with jit.using(True):
        a = fiedler(n, pairs, w, guess=guess)
    with jit.using(False):
        b = fiedler(n, pairs, w, guess=guess)
    assert a[0] == b[0] and np.array_equal(a[1], b[1])


@pytest.mark.parametrize("method", ["auto", "lapack"])
def test_strategy_parameter_selects_the_solver(method: str, monkeypatch) -> None:  # noqa: ANN001
    """``fiedler_method: lapack`` never runs the small solver (the trajectories of before);
    ``auto`` runs it, in the fused kernel or in ``fiedler``."""
    import importlib

    import tether.continuous.connectivity.kernels as kernels
    import tether.continuous.connectivity.weights as weights
    from tether.config import load_scenario
    from tether.runner import build
    from tether.sim import simulate

    fiedler_module = importlib.import_module("tether.graph.fiedler")  # not the function
    calls = {"small": 0}
    original_small, original_fused = fiedler_module._small, kernels.evaluate_fiedler_kernel
    original_free = kernels.evaluate_fiedler_free_kernel

    def counting_small(*args):  # noqa: ANN002, ANN202
        calls["small"] += 1
        return original_small(*args)

    def counting_fused(*args):  # noqa: ANN002, ANN202
        calls["small"] += not args[16]  # lapack=False: the small solver first
        return original_fused(*args)

    def counting_free(*args):  # noqa: ANN002, ANN202
        calls["small"] += not args[8]  # the same without obstacles
        return original_free(*args)

    monkeypatch.setattr(fiedler_module, "_small", counting_small)
    counted = (kernels.evaluate_kernel, counting_fused, counting_free, kernels.no_obstacles)
    monkeypatch.setattr(weights, "_kernels", lambda: counted)
    sc = load_scenario("multi_target_empty")
    sc.team.n_robots = 20
    sc.strategy.params["fiedler_method"] = method
    b = build(sc, sc.seed)
    simulate(b.world, b.sensor, b.strategy, b.initial, dt_s=sc.sim.dt_s, max_steps=15,
             rng=b.rng, collision_distance_m=sc.sim.collision_distance_m)  # fmt: skip
    assert (calls["small"] > 0) == (method == "auto")


def test_multi_target_defaults_to_the_small_solver_as_connectivity_does() -> None:
    """The Fig. 9 campaign in the docs runs with the certified small solver;
    ``fiedler_method: lapack`` (``dsyevr`` at every sub-step) stays available."""
    from tether.continuous.connectivity.strategy import ConnectivityStrategyParams
    from tether.continuous.exploration.params import MultiTargetParams

    assert MultiTargetParams().fiedler_method == "auto"
    assert MultiTargetParams(fiedler_method="lapack").fiedler_method == "lapack"
    assert ConnectivityStrategyParams().fiedler_method == "auto"
