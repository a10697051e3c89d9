"""Strategy multi_target end to end: roles, anchors, connectivity, completeness, targets."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.parquet as pq
import pytest

from tether.config import scenario_from_dict
from tether.continuous.exploration.motion import traveling_forces
from tether.continuous.exploration.roles import PRIME, SECONDARY
from tether.continuous.exploration.strategy import MultiTargetStrategy
from tether.continuous.exploration.targets import TargetBook
from tether.record import TrajectoryRecorder
from tether.runner import build, run
from tether.sim import simulate


def scenario(seed: int, *, n: int = 7, targets: dict | None = None, **params: Any) -> dict:
    """A small empty-space trial: 20 m x 20 m x 8 m, Table 2 outdoor."""
    return {
        "name": "mt-small",
        "seed": seed,
        "world": {"scene": "empty", "dim": 3,
                  "params": {"size_m": [20.0, 20.0], "height_m": 8.0, "resolution_m": 0.5}},
        "team": {"n_robots": n},
        "sensing": {"range_m": 6.0, "occlusion": False, "noise": "none"},
        "sim": {"dt_s": 0.1, "max_steps": 1500, "collision_distance_m": 1.0},
        "strategy": {"name": "multi_target", "params": {
            "preset": "outdoor",
            "targets": targets or {"kind": "paper_random", "params": {
                "explorers": [2, 2, 1, 1], "height_m": [2.0, 6.0], "clearance_m": 2.0}},
            "start": {"center_m": [10.0, 10.0, 4.0]},
            **params}},
        "output": {"record_every": 1, "figures": False},
    }  # fmt: skip


@pytest.fixture(scope="module")
def trials(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    """Six small trials (three with 10 % message loss), run once for the tests below."""
    out = []
    for seed in range(6):
        data = scenario(seed, messages={"loss_probability": 0.1 if seed % 2 else 0.0})
        path = tmp_path_factory.mktemp("mt") / f"s{seed}"
        run(scenario_from_dict(data, f"small-{seed}.yaml"), out_dir=path)
        out.append(path)
    return out


def test_every_target_is_reached_connected_and_without_collision(trials: list[Path]) -> None:
    for path in trials:
        s = json.loads((path / "summary.json").read_text())
        assert s["targets_total"] == 6 and s["targets_reached"] == 6, path
        assert s["completion_time_s"] is not None and s["completion_time_s"] <= s["sim_time_s"]
        assert s["min_lambda2_weighted"] > 0  # lambda2_min = 0: never disconnected
        assert s["collisions"] == 0 and s["min_robot_distance_m"] > 1.0  # Rc = 1 m
        steps = pq.read_table(path / "steps.parquet").to_pydict()
        assert min(steps["lambda2_weighted"]) > 0


def test_at_most_one_prime_traveler_at_every_step(trials: list[Path]) -> None:
    for path in trials:
        robots = pq.read_table(path / "robots.parquet").to_pydict()
        step, role = np.asarray(robots["step"]), np.asarray(robots["role"])
        primes = np.bincount(step[role == "prime"], minlength=step.max() + 1)
        assert primes.max() == 1
        assert primes.sum() > 0


def test_anchors_outside_their_ball_are_counted_exactly(trials: list[Path]) -> None:
    """``anchor_outside_steps`` (the bounded anchor force can be overpowered) against the
    recorded positions and the target each anchor took (every step is recorded here)."""
    rz = 1.8
    for path in trials:
        events = pq.read_table(path / "events.parquet").to_pylist()
        robots = pq.read_table(path / "robots.parquet").to_pydict()
        pos = np.stack([robots["x_m"], robots["y_m"], robots["z_m"]], axis=1)
        step, robot, role = (np.asarray(robots[k]) for k in ("step", "robot", "role"))
        taken = sorted((e["step"], e["robot"], e["position_m"]) for e in events
                       if e["kind"] == "target_taken")  # fmt: skip
        outside, checked = set(), 0
        for k in np.flatnonzero((role == "anchor") & (step > 0)):
            current = [z for s, r, z in taken if r == robot[k] and s <= step[k]][-1]
            if np.linalg.norm(pos[k] - current) >= rz:
                outside.add(int(step[k]))
            checked += 1
        assert checked > 20
        summary = json.loads((path / "summary.json").read_text())
        assert summary["anchor_outside_steps"] == len(outside), path


def test_the_paper_s_anchor_force_keeps_every_anchor_inside_its_ball() -> None:
    """``max_anchor_force_n: null`` is eq. (7) as printed: unbounded at ``Rz``."""
    data = scenario(0, max_anchor_force_n=None)
    built = build(scenario_from_dict(data, "paper-anchor.yaml"))
    rec = TrajectoryRecorder(every=1)
    res = simulate(built.world, built.sensor, built.strategy, built.initial, dt_s=0.1,
                   max_steps=800, rng=built.rng, recorder=rec)  # fmt: skip
    assert res.strategy_metrics["anchor_outside_steps"] == 0
    assert res.strategy_metrics["targets_reached"] >= 3


def test_the_election_winner_had_the_shortest_remaining_path(trials: list[Path]) -> None:
    """Every election names one of its candidates (the flood's minimum)."""
    for path in trials:
        for e in pq.read_table(path / "events.parquet").to_pylist():
            if e["kind"] == "election" and e["winner"] >= 0:
                assert e["winner"] in e["candidates"]


def test_paper_random_targets_do_not_depend_on_the_team_size() -> None:
    def targets(n: int, seed: int) -> list[list[float]]:
        s = build(scenario_from_dict(scenario(seed, n=n), "x.yaml"))
        return [z.position_m.tolist() for q in s.strategy.targets.queues for z in q]

    assert targets(7, 3) == targets(12, 3)
    assert targets(7, 3) != targets(7, 4)
    assert len(targets(7, 3)) == 6


def test_traveling_force_is_local() -> None:
    """Robot i's f_i depends on its own state, path, f_lambda_i and Lambda_hat_i only."""
    data = scenario(0)
    built = build(scenario_from_dict(data, "x.yaml"))
    strat: MultiTargetStrategy = built.strategy
    strat.reset(built.world, built.initial, built.rng)
    q = built.initial.positions.copy()
    rng = np.random.default_rng(0)
    v = rng.normal(size=q.shape)
    f_lam = rng.normal(size=q.shape)
    lam_hat = rng.uniform(size=len(q))
    strat.planner.role[:] = SECONDARY
    strat.planner.role[0] = PRIME
    base = traveling_forces(q, v, f_lam, strat.planner, lam_hat, strat.params)
    for i in range(len(q)):
        for j in range(len(q)):
            if i == j:
                continue
            q2, v2, f2, l2 = q.copy(), v.copy(), f_lam.copy(), lam_hat.copy()
            q2[j] += 30.0  # move robot j far away, with its own force inputs changed too
            v2[j] += 1.0
            f2[j] *= -3.0
            l2[j] = 1.0 - l2[j]
            got = traveling_forces(q2, v2, f2, strat.planner, l2, strat.params)
            assert np.array_equal(got[i], base[i])


def test_targets_added_while_running_and_scheduled_ones_are_visited() -> None:
    sched = {"kind": "schedule", "params": {"targets": [
        {"robot": 2, "position_m": [14.0, 10.0, 4.0], "at_s": 5.0, "stay_s": 1.0}]}}  # fmt: skip
    built = build(scenario_from_dict(scenario(1, targets=sched), "x.yaml"))
    strat: MultiTargetStrategy = built.strategy

    class AddAtStep50(TrajectoryRecorder):
        def record(self, rec, *args: Any) -> None:  # noqa: ANN001
            super().record(rec, *args)
            if rec.step == 50:
                strat.add_target(4, [6.0, 12.0, 3.0], stay_s=1.0)

    recorder = AddAtStep50()
    result = simulate(built.world, built.sensor, strat, built.initial, dt_s=0.1,
                      max_steps=1500, rng=built.rng, recorder=recorder)  # fmt: skip
    m = result.strategy_metrics
    assert m["targets_total"] == 2 and m["targets_reached"] == 2
    taken = {e["robot"]: e["step"] for e in recorder.events if e["kind"] == "target_taken"}
    assert taken[2] >= 50 and taken[4] >= 50  # appeared at 5 s; added at step 50


def test_unreachable_and_expired_targets_are_dropped_and_the_team_moves_on(tmp_path) -> None:
    # a closed hollow box (walls every 0.25 m): its inside is free but cannot be reached
    g = np.arange(13.0, 17.01, 0.25)
    shell = np.array([(x, y, z) for x in g for y in g for z in np.arange(2.0, 6.01, 0.25)
                      if min(x - 13, 17 - x, y - 13, 17 - y, z - 2, 6 - z) < 1e-9])  # fmt: skip
    np.save(tmp_path / "box.npy", shell)
    fixed = {"kind": "fixed", "params": {"queues": [
        {"robot": 0, "targets": [[15.0, 15.0, 4.0], [8.0, 10.0, 4.0]], "stay_s": 1.0},
        {"robot": 1, "targets": [[2.0, 2.0, 2.0]], "stay_s": 1.0, "timeout_s": 3.0},
        {"robot": 1, "targets": [[9.0, 11.0, 4.0]], "stay_s": 1.0}]}}  # fmt: skip
    data = scenario(2, targets=fixed)
    data["world"] = {"scene": "user_points", "dim": 3, "params": {
        "path": str(tmp_path / "box.npy"), "bounds_m": [[0, 0, 0], [20, 20, 8]],
        "resolution_m": 0.25}}  # fmt: skip
    data["strategy"]["params"]["start"] = {"center_m": [6.0, 8.0, 4.0]}
    built = build(scenario_from_dict(data, "x.yaml"))
    recorder = TrajectoryRecorder()
    result = simulate(built.world, built.sensor, built.strategy, built.initial, dt_s=0.1,
                      max_steps=1500, rng=built.rng, recorder=recorder)  # fmt: skip
    reasons = {(e["robot"], e["reason"]) for e in recorder.events if e["kind"] == "target_dropped"}
    # robot 0's first target is inside the sealed box: no path; robot 1's first is 6 m
    # away with 3 s to get there and a team to drag along: it expires
    assert (0, "unreachable") in reasons and (1, "expired") in reasons
    m = result.strategy_metrics
    assert m["targets_reached"] == 2 and m["targets_dropped"] == 2
    assert m["completion_time_s"] is None and result.steps < 1500  # ended, not completed


def test_book_rejects_bad_targets() -> None:
    book = TargetBook.empty(3)
    with pytest.raises(ValueError, match="robot"):
        book.add(5, [0, 0, 0])
    with pytest.raises(ValueError, match="finite"):
        book.add(0, [0, np.nan, 0])
    with pytest.raises(ValueError, match="stay_s"):
        book.add(0, [0, 0, 0], stay_s=-1)


@pytest.mark.parametrize("replan_s", [20.0, None])
def test_a_stalled_prime_plans_its_path_again_from_where_it_is(replan_s: float | None) -> None:
    """``replan_stalled_s``: a prime whose path has not shrunk plans again from its position
    every ``replan_stalled_s``; the stall clock runs on, so the watchdog still drops it."""
    built = build(scenario_from_dict(scenario(0, replan_stalled_s=replan_s), "x.yaml"))
    strat: MultiTargetStrategy = built.strategy
    strat.reset(built.world, built.initial, built.rng)
    pl = strat.planner
    i = int(np.flatnonzero([p is not None for p in pl.path])[0])
    pl.set_role(i, PRIME, 0.0)
    q = built.initial.positions.copy()
    q[i] += 0.5  # pushed off its path's start, and it stays there: no progress
    strat.drain_events()
    replans, dropped = [], None
    for k in range(700):
        pl.update(q, k / 10)
        for e in strat.drain_events():
            if e.get("robot") == i and e["kind"] == "replan":
                replans.append(e["t_s"])
                assert np.allclose(pl.path[i].points[0], q[i])  # from where it is
            if e.get("robot") == i and e["kind"] == "target_dropped":
                dropped = (e["t_s"], e["reason"])
    assert dropped is not None and dropped[1] == "stalled" and 60.0 < dropped[0] < 60.2
    assert replans == ([] if replan_s is None else [20.0, 40.0, 60.0])


def test_a_dropped_target_ends_the_mission_and_is_counted_not_hidden() -> None:
    """The run ends when every target is reached or dropped (an expired one here);
    ``targets_dropped`` and ``targets_pending`` say what it cost, and the mission has no
    ``completion_time_s``: it was not completed."""
    queues = [
        {"robot": 0, "targets": [[2.5, 12.5, 1.2]], "stay_s": 1.0},
        {"robot": 1, "targets": [[2.05, 11.85, 1.0]], "stay_s": 1.0, "timeout_s": 0.5},
    ]
    data = {"name": "drop", "seed": 1,
            "world": {"scene": "office", "dim": 3, "params": {"resolution_m": 0.1, "seed": 0}},
            "sensing": {"range_m": 2.5}, "team": {"n_robots": 6},
            "sim": {"dt_s": 0.1, "max_steps": 600},
            "strategy": {"name": "multi_target", "params": {
                "preset": "office", "start": {"center_m": [2.05, 11.85, 1.2]},
                "targets": {"kind": "fixed", "params": {"queues": queues}}}}}  # fmt: skip
    b = build(scenario_from_dict(data, "drop.yaml"))
    r = simulate(b.world, b.sensor, b.strategy, b.initial, dt_s=0.1, max_steps=600, rng=b.rng)
    m = r.strategy_metrics
    assert (m["targets_total"], m["targets_reached"], m["targets_dropped"]) == (2, 1, 1)
    assert m["targets_pending"] == 0
    assert m["completion_time_s"] is None and r.steps < 600
    assert r.sim_time_s == pytest.approx(r.steps * 0.1)
    b = build(scenario_from_dict(data, "drop.yaml"))
    r = simulate(b.world, b.sensor, b.strategy, b.initial, dt_s=0.1, max_steps=3, rng=b.rng)
    assert r.strategy_metrics["completion_time_s"] is None
    assert r.strategy_metrics["targets_pending"] >= 1


def test_no_prime_vacancy_outlasts_a_result_flood(trials: list[Path]) -> None:
    """Sec. 3.3: after an election no prime exists only until the result reaches the
    winner, at most ``N - 1`` rounds (one round per step; the lossless trials)."""
    for path in trials[::2]:
        s = json.loads((path / "summary.json").read_text())
        assert s["elections"] >= 3
        assert s["longest_prime_vacancy_steps"] <= s["n_robots"] - 1, path


def test_lambda_p_is_defined_only_while_a_prime_travels(trials: list[Path]) -> None:
    """``prime_efficiency`` (Lambda_p, eq. (12)) is a number exactly when a prime exists
    and has a path; no prime, or one holding at its target, pins nothing."""
    for path in trials:
        steps = pq.read_table(path / "steps.parquet").to_pydict()
        prime = np.asarray(steps["prime"])
        eff = np.asarray(steps["prime_efficiency"], dtype=float)
        assert np.all(np.isnan(eff[prime < 0]))
        assert np.isfinite(eff[prime >= 0]).mean() > 0.2  # elections hold primes at targets
        assert np.all((eff[np.isfinite(eff)] >= 0) & (eff[np.isfinite(eff)] <= 1))


def test_the_experiment_preset_has_the_paper_s_consensus_gain() -> None:
    """Sec. 4.2: "We chose k_Lambda = 1"; the simulation presets keep the faster 5."""
    from tether.continuous.exploration.params import MultiTargetParams

    assert MultiTargetParams(preset="experiment").k_lambda_per_s == 1.0
    assert MultiTargetParams(preset="outdoor").k_lambda_per_s == 5.0
    assert MultiTargetParams(preset="experiment", k_lambda_per_s=3.0).k_lambda_per_s == 3.0
