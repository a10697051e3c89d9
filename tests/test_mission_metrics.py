"""Mission metrics against hand-computed cases and brute-force oracles on tiny grids."""

from __future__ import annotations

import math

import numpy as np
import pytest

from tether.mission.log import MissionLog
from tether.mission.metrics import QUANTILES, mission_metrics


def corridor_log() -> MissionLog:
    """A 1 x 10 corridor; the robot senses cell k at step k and reaches the BS at 0, 3, 7."""
    log = MissionLog(np.ones((1, 10), bool), 1)
    base = np.zeros(10, bool)
    for step in range(10):
        linked = step in (0, 3, 7)
        if linked:
            base[: step + 1] = True
        log.record(step, [(0, np.array([step]))], base.copy(), [[step * 0.5, 0.0]], [linked], True)
    return log


def test_corridor_latencies_by_hand() -> None:
    m = mission_metrics(corridor_log(), dt_s=2.0)
    # cells 1, 2, 3 wait for step 3; 4..7 for step 7; 8, 9 are never delivered
    delivered = [0, 2, 1, 0, 3, 2, 1, 0]
    assert m["latency_mean_s"] == pytest.approx(2.0 * sum(delivered) / 8)
    assert m["latency_max_s"] == 6.0
    assert m["latency_undelivered_frac"] == pytest.approx(0.2)
    q = dict(zip(QUANTILES, m["latency_quantiles_s"], strict=True))
    # sorted (s): 0 0 0 2 2 4 4 6 inf inf
    assert (q[0.0], q[0.3], q[0.5], q[0.8]) == (0.0, 0.0, 2.0, 6.0)
    assert q[0.85] is None and q[1.0] is None
    # the BS knows 4/10 at step 3 and 8/10 at step 7; the team 5/10 at step 4
    assert m["base_time_to_50pct_s"] == 14.0 and m["base_time_to_90pct_s"] is None
    assert m["team_time_to_50pct_s"] == 8.0 and m["team_time_to_90pct_s"] == 16.0
    assert m["team_time_to_99pct_s"] == 18.0
    assert m["base_explored_final"] == pytest.approx(0.8)
    assert m["linked_to_base_frac"] == [pytest.approx(2 / 9)]
    assert m["path_length_m"] == [pytest.approx(4.5)]
    assert m["overlap_rate"] == 0.0 and m["coverage_std"] == 0.0


def brute_force(log: MissionLog, sensed_steps: list, base_steps: list, dt_s: float) -> dict:
    """Every metric by loops over cells, robots and steps, from the raw inputs."""
    n, reach = log.n, np.flatnonzero(log.reachable).tolist()
    first: dict[tuple[int, int], int] = {}
    for step, scans in enumerate(sensed_steps):
        for r, cells in scans:
            for c in cells.tolist():
                first.setdefault((r, c), step)
    base_first: dict[int, int] = {}
    for step, known in enumerate(base_steps):
        for c in np.flatnonzero(known).tolist():
            base_first.setdefault(c, step)
    lat, undelivered, multi, sensed = [], 0, 0, 0
    for c in reach:
        robots = [first[(r, c)] for r in range(n) if (r, c) in first]
        if not robots:
            continue
        sensed += 1
        multi += len(robots) >= 2
        if c in base_first:
            lat.append((base_first[c] - min(robots)) * dt_s)
        else:
            undelivered += 1
    cover = [sum((r, c) in first for c in reach) / len(reach) for r in range(n)]
    mean = sum(cover) / n
    lengths = []
    for r in range(n):
        p = [pos[r] for pos in log.positions_m]
        lengths.append(sum(math.dist(a, b) for a, b in zip(p, p[1:], strict=False)))
    base_series = [sum(c in base_first and base_first[c] <= t for c in reach) for t in
                   range(len(base_steps))]  # fmt: skip
    t50 = next((t * dt_s for t, k in enumerate(base_series) if k >= 0.5 * len(reach)), None)
    steps = len(sensed_steps) - 1
    linked = [sum(bool(log.linked[t][r]) for t in range(1, steps + 1)) / steps for r in range(n)]
    return {
        "latency_mean_s": sum(lat) / len(lat) if lat else None,
        "latency_max_s": max(lat) if lat else None,
        "latency_undelivered_frac": undelivered / sensed if sensed else 0.0,
        "latency_quantiles_s": [
            None if np.isinf(v) else float(v)
            for v in np.quantile(lat + [np.inf] * undelivered, QUANTILES, method="inverted_cdf")
        ],
        "overlap_rate": multi / sensed if sensed else 0.0,
        "coverage_std": math.sqrt(sum((x - mean) ** 2 for x in cover) / n),
        "path_length_m": lengths,
        "base_time_to_50pct_s": t50,
        "linked_to_base_frac": linked,
        "team_explored_final": sum(any((r, c) in first for r in range(n)) for c in reach)
        / len(reach),
        "base_explored_final": sum(c in base_first for c in reach) / len(reach),
    }


@pytest.mark.parametrize("seed", range(12))
def test_random_missions_match_brute_force(seed: int) -> None:
    rng = np.random.default_rng(seed)
    shape, n, steps, dt_s = (4, 5), int(rng.integers(1, 4)), int(rng.integers(2, 12)), 0.5
    reachable = rng.random(shape) < 0.7
    reachable.flat[0] = True
    log = MissionLog(reachable, n)
    own = np.zeros((n, reachable.size), bool)  # what each robot holds, not yet at the BS
    base = np.zeros(reachable.size, bool)
    sensed_steps, base_steps = [], []
    pos = rng.random((n, 2)) * 3
    for step in range(steps + 1):
        # a scan may name a cell twice (rays of a depth sensor cross the same cells)
        scans = [(r, rng.choice(reachable.size, size=int(rng.integers(0, 5)), replace=True))
                 for r in range(n) if rng.random() < 0.8]  # fmt: skip
        for r, cells in scans:
            own[r, cells] = True
        linked = rng.random(n) < 0.4
        base |= own[linked].any(axis=0)
        pos = pos + rng.normal(size=(n, 2)) * (step > 0)
        log.record(step, scans, base.reshape(shape), pos, linked, bool(rng.random() < 0.5))
        sensed_steps.append(scans)
        base_steps.append(base.copy())
    got = mission_metrics(log, dt_s)
    want = brute_force(log, sensed_steps, base_steps, dt_s)
    for key, value in want.items():
        if value is None:
            assert got[key] is None, key
        else:
            assert got[key] == pytest.approx(value, abs=1e-9), key


def test_steps_out_of_order_refused() -> None:
    log = MissionLog(np.ones((2, 2), bool), 1)
    with pytest.raises(ValueError, match="in order"):
        log.record(1, [], np.zeros((2, 2), bool), [[0.0, 0.0]], [True], True)
