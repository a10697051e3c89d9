"""Recruiting helpers for a stalled prime traveler (``tether.continuous.exploration.recruit``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import networkx as nx
import numpy as np
import pytest

from tether import jit
from tether.comm import CommParams, MessageLayer
from tether.config import load_scenario
from tether.continuous.exploration.recruit import (
    HelpFlood,
    RequestDepth,
    help_depth,
    help_force,
    help_rows,
)
from tether.record import TrajectoryRecorder
from tether.runner import build
from tether.sim import simulate


def random_connected_pairs(rng: np.random.Generator, n: int) -> np.ndarray:
    """A random tree plus a few chords."""
    pairs = {(int(rng.integers(i)), i) for i in range(1, n)}
    for _ in range(n // 3):
        a, b = sorted(rng.choice(n, 2, replace=False).tolist())
        pairs.add((a, b))
    return np.array(sorted(pairs))


def test_the_request_deepens_with_the_stall_and_is_capped() -> None:
    depths = [help_depth(s, 10.0, 4) for s in np.arange(0.0, 100.0, 0.5)]
    assert depths[:20] == [0] * 20  # nothing before help_after_s
    assert help_depth(10.0, 10.0, 4) == 1 and help_depth(29.9, 10.0, 4) == 2
    assert np.all(np.diff(depths) >= 0) and max(depths) == 4
    assert help_depth(float("nan"), 10.0, 4) == 0


def _crawl(depth: RequestDepth, bursts: list[tuple[float, float]], prime: int = 3) -> list[int]:
    """Feed ``(stall, moving)`` bursts at 10 Hz: stalled for ``stall`` s, then progressing."""
    seen = []
    for stall_s, moving_s in bursts:
        seen += [depth.update(prime, k / 10)[0] for k in range(int(round(stall_s * 10)))]
        seen += [depth.update(prime, 0.0)[0] for _ in range(int(round(moving_s * 10)))]
    return seen


def test_a_prime_crawling_in_bursts_keeps_and_deepens_its_request_until_its_turn_ends() -> None:
    bursts = [(35.0, 2.0)] * 5  # stalls of 35 s (1 hop after 20 s), short progress between
    plain = _crawl(RequestDepth(20.0, 8, until="progress"), bursts)
    sticky = RequestDepth(20.0, 8, until="arrival")
    kept = _crawl(sticky, bursts)
    assert max(plain) == 1 and plain[-1] == 0  # every request starts again at 1 hop and ends
    assert max(kept) == 5  # one hop deeper per stall: 1, 2, 3, 4, 5
    assert min(kept[200:]) >= 1  # never dropped once asked, progress or not
    assert np.all(np.diff(kept) >= 0)
    assert max(_crawl(RequestDepth(20.0, 3, until="arrival"), bursts)) == 3  # the cap
    assert sticky.update(7, 0.0) == (0, "ended")  # another prime: the old request ends


def test_a_new_prime_starts_its_request_from_one_hop() -> None:
    depth = RequestDepth(20.0, 8, until="arrival")
    _crawl(depth, [(45.0, 1.0)] * 3, prime=3)  # prime 3 reached 6 hops
    assert max(_crawl(depth, [(25.0, 1.0)], prime=5)) == 1
    assert depth.update(-1, 0.0) == (0, "ended")  # no prime: no request
    assert RequestDepth(None, 8).update(2, 1e3) == (0, None)  # help switched off


@pytest.mark.parametrize("seed", range(8))
def test_helpers_are_the_robots_within_depth_hops_following_a_closer_neighbour(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n, depth = int(rng.integers(6, 25)), int(rng.integers(1, 5))
    pairs = random_connected_pairs(rng, n)
    q = rng.uniform(0, 50, (n, 3))
    prime = int(rng.integers(n))
    flood = HelpFlood(n, 3, MessageLayer(n, CommParams(), rng))
    for _ in range(depth + 1):  # one hop per round
        flood.round(pairs, q, prime, depth)
    hops = nx.single_source_shortest_path_length(nx.Graph(pairs.tolist()), prime)
    expect = sorted(i for i, h in hops.items() if 1 <= h <= depth)
    assert flood.helpers(np.ones(n, dtype=bool)).tolist() == expect
    for i in expect:
        j = flood.parent[i]
        assert (min(i, j), max(i, j)) in set(map(tuple, pairs.tolist()))  # a neighbour
        assert hops[j] == hops[i] - 1  # one hop closer to the prime
        candidates = [k for k in range(n) if hops.get(k) == hops[i] - 1 and
                      (min(i, k), max(i, k)) in set(map(tuple, pairs.tolist()))]  # fmt: skip
        assert j == min(candidates)  # ties to the lower index
        np.testing.assert_array_equal(flood.parent_m[i], q[j])  # the parent's broadcast
    # only robots allowed to help (connectors, secondaries) are returned
    may = rng.random(n) < 0.5
    assert set(flood.helpers(may).tolist()) == {i for i in expect if may[i]}


def test_the_request_ends_when_the_prime_makes_progress() -> None:
    n = 10
    pairs = np.array([(i, i + 1) for i in range(n - 1)])
    q = np.arange(n * 3, dtype=float).reshape(n, 3)
    flood = HelpFlood(n, 3, MessageLayer(n, CommParams(), np.random.default_rng(0)))
    for _ in range(5):
        flood.round(pairs, q, 0, 4)
    assert flood.helpers(np.ones(n, dtype=bool)).tolist() == [1, 2, 3, 4]
    for _ in range(6):  # stale hop counts may bounce between helpers, but only up to the depth
        flood.round(pairs, q, 0, 0)
    assert len(flood.helpers(np.ones(n, dtype=bool))) == 0
    layer_round = flood.layer.round
    flood.round(pairs, q, 0, 0)  # quiet: the round is skipped
    assert flood.layer.round == layer_round


def test_lost_messages_slow_the_request_but_never_reach_beyond_the_depth() -> None:
    rng = np.random.default_rng(3)
    n, depth = 12, 3
    pairs = np.array([(i, i + 1) for i in range(n - 1)])
    q = rng.uniform(0, 10, (n, 3))
    flood = HelpFlood(n, 3, MessageLayer(n, CommParams(loss_probability=0.4), rng))
    seen: set[int] = set()
    for _ in range(60):
        flood.round(pairs, q, 0, depth)
        seen |= set(flood.helpers(np.ones(n, dtype=bool)).tolist())
    assert seen == {1, 2, 3}


def test_help_force_pulls_to_the_keep_distance_bounded_and_damped() -> None:
    rng = np.random.default_rng(0)
    q, parent = rng.uniform(-5, 5, (200, 3)), rng.uniform(-5, 5, (200, 3))
    v = np.zeros_like(q)
    f = help_force(q, v, parent, keep_m=2.5, kp=4.0, kv=4.0, max_force_n=10.0)
    d = np.linalg.norm(parent - q, axis=1)
    assert np.all(np.linalg.norm(f, axis=1) <= 10.0 + 1e-12)
    assert np.all(f[d <= 2.5] == 0.0)  # close enough: a plain connector
    far = d > 2.5
    cos = np.einsum("ij,ij->i", f[far], parent[far] - q[far])
    assert np.all(cos > 0)  # towards the parent
    expect = np.minimum(4.0 * (d[far] - 2.5), 10.0)
    np.testing.assert_allclose(np.linalg.norm(f[far], axis=1), expect, rtol=1e-12)
    # moving away from the parent is damped: the force grows
    away = -(parent - q) / np.maximum(d, 1e-12)[:, None]
    g = help_force(q, 0.1 * away, parent, keep_m=2.5, kp=4.0, kv=4.0, max_force_n=np.inf)
    ff = help_force(q, v, parent, keep_m=2.5, kp=4.0, kv=4.0, max_force_n=np.inf)
    assert np.all(np.linalg.norm(g[far], axis=1) > np.linalg.norm(ff[far], axis=1))


DEADLOCK = Path(__file__).parent / "data" / "deadlock_town.yaml"


def run_deadlock(max_steps: int, **params: Any) -> tuple[dict, TrajectoryRecorder, np.ndarray]:
    sc = load_scenario(DEADLOCK)
    for key, value in params.items():
        sc.strategy.params[key] = value
    built = build(sc)
    recorder = TrajectoryRecorder()
    result = simulate(built.world, built.sensor, built.strategy, built.initial, dt_s=0.1,
                      max_steps=max_steps, rng=built.rng,
                      collision_distance_m=1.0, recorder=recorder)  # fmt: skip
    target = np.array([48.258, 16.711, 2.886])
    dist = np.array([np.linalg.norm(q[7] - target) for q in recorder.positions])
    out = {**result.strategy_metrics, "connected_all_steps": result.connected_all_steps,
           "collisions": sum(r.collisions for r in result.records)}  # fmt: skip
    return out, recorder, dist


def test_helpers_bring_a_prime_held_at_a_roof_edge_to_its_target_sooner() -> None:
    """A prime held at a roof edge by one link (a Fig. 9 town team). Without helpers it
    gets there on its own (the stable integrator; the old one stalled here for good);
    with helpers asked after 5 s of stall it gets there sooner, every invariant kept."""
    off, _, _ = run_deadlock(500, help_after_s=None, stall_timeout_s=None)
    assert off["targets_reached"] == 1 and off["help_requests"] == 0
    on, rec, _ = run_deadlock(500, help_after_s=5.0)
    assert on["targets_reached"] == 1
    assert on["completion_time_s"] < off["completion_time_s"] - 5.0
    assert on["connected_all_steps"] and on["collisions"] == 0 and on["controller_success"]
    asked = [e for e in rec.events if e["kind"] == "help_requested"]
    assert asked and all(e["robot"] == 7 for e in asked)
    assert on["help_requests"] >= 1 and on["helper_robot_s"] > 0


def test_helpers_move_the_same_with_the_compiled_sub_step_and_without() -> None:
    """The fused sub-step (kernels on) must apply the helpers' force as the reference does."""
    pytest.importorskip("numba")
    runs = []
    for on in (True, False):
        with jit.using(on):
            metrics, rec, _ = run_deadlock(160, help_after_s=5.0)  # the request: step 105
        runs.append((metrics, np.array(rec.positions)))
    (m_on, q_on), (m_off, q_off) = runs
    assert m_on["helper_robot_s"] > 0 and m_on["help_requests"] == 1
    np.testing.assert_array_equal(q_on, q_off)


def test_help_lambda_factor_scales_only_the_helpers_force_the_same_compiled_or_not() -> None:
    """``help_lambda_factor``: nothing changes before the first request; then the helpers
    move differently, lambda2 stays above 0, and the fused sub-step (kernels on) applies
    the factor exactly as the reference does."""
    pytest.importorskip("numba")
    with jit.using(True):
        _, base, _ = run_deadlock(160, help_after_s=5.0, help_lambda_factor=None)
    runs = []
    for on in (True, False):
        with jit.using(on):
            metrics, rec, _ = run_deadlock(160, help_after_s=5.0, help_lambda_factor=0.1)
        runs.append((metrics, np.array(rec.positions)))
    (m_on, q_on), (m_off, q_off) = runs
    np.testing.assert_array_equal(q_on, q_off)
    q_base = np.array(base.positions)
    asked = min(e["step"] for e in base.events if e["kind"] == "help_requested")
    np.testing.assert_array_equal(q_on[: asked + 1], q_base[: asked + 1])
    assert np.abs(q_on[-1] - q_base[-1]).max() > 1e-3  # the helpers moved otherwise
    assert m_on["helper_robot_s"] > 0 and m_on["min_lambda2_weighted"] > 0
    assert m_on["connected_all_steps"] and m_on["collisions"] == 0


def test_help_lambda_factor_defaults_per_preset_and_can_be_switched_off() -> None:
    """Outdoors a helper's connectivity force is scaled by 0.1 unless a scenario says
    otherwise; the office preset does not scale it (docs/explanation/multi_target.md, "Helpers")."""
    from tether.continuous.exploration.params import MultiTargetParams

    assert MultiTargetParams().help_lambda_factor == 0.1
    assert MultiTargetParams(preset="outdoor").help_lambda_factor == 0.1
    assert MultiTargetParams(preset="office").help_lambda_factor is None
    assert MultiTargetParams(preset="outdoor", help_lambda_factor=None).help_lambda_factor is None
    assert MultiTargetParams(preset="office", help_lambda_factor=0.5).help_lambda_factor == 0.5


@pytest.mark.skipif(not jit.available(), reason="needs numba")
@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("max_force_n", [10.0, np.inf])
@pytest.mark.parametrize("lambda_factor", [None, 0.3])
def test_help_rows_compiled_is_the_numpy_path(
    dim: int, max_force_n: float, lambda_factor: float | None
) -> None:
    """The compiled helpers' rows equal the numpy path bit for bit; the other rows are
    left as they were; a helper on its parent (distance 0) and one within the keep
    distance get no pull."""
    rng = np.random.default_rng(dim)
    n = 30
    q, v = rng.uniform(-8, 8, (n, dim)), rng.normal(0, 2, (n, dim))
    f_ext, f_lambda = rng.normal(0, 5, (n, dim)), rng.normal(0, 50, (n, dim))
    helpers = np.sort(rng.choice(n, 12, replace=False))
    parents = rng.uniform(-8, 8, (12, dim))
    parents[0] = q[helpers[0]]  # on its parent
    parents[1] = q[helpers[1]] + 0.5  # within keep_m
    kw = {"keep_m": 2.5, "kp": 4.0, "kv": 4.0, "max_force_n": max_force_n,
          "lambda_factor": lambda_factor}  # fmt: skip
    with jit.using(True):
        got = help_rows(q, v, f_ext.copy(), f_lambda, helpers, parents, **kw)
    with jit.using(False):
        want = help_rows(q, v, f_ext.copy(), f_lambda, helpers, parents, **kw)
    assert np.array_equal(got, want)
    others = np.setdiff1d(np.arange(n), helpers)
    assert np.array_equal(got[others], f_ext[others])
    g = 1.0 if lambda_factor is None else lambda_factor
    np.testing.assert_allclose(got[helpers[:2]], -(1.0 - g) * f_lambda[helpers[:2]])
