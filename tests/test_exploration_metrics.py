"""What researchers measure: time to a share of the map, where robot time goes, episodes.

Every key is recomputed from the run folder's tables (recorded at every step) and
compared with ``summary.json``; the four time shares sum to 1 on every run.
"""

from __future__ import annotations

import numpy as np
import pyarrow.parquet as pq
import pytest

from tether.config import load_scenario, scenario_from_dict
from tether.recurrent.exploration.metrics import RobotState, classify, episodes, first_reach
from tether.runner import run

SHARES = ("moving", "relaying", "waiting", "returning")


def test_episodes_and_first_reach() -> None:
    assert episodes(np.array([0, 1, 1, 0, 1], bool)) == [2, 1]
    assert episodes(np.array([1, 1, 1], bool)) == [3]
    assert episodes(np.zeros(4, bool)) == []
    assert first_reach(np.array([0.1, 0.5, 0.7]), 0.5) == 1
    assert first_reach(np.array([0.1, 0.4]), 0.5) is None


def test_classify_precedence() -> None:
    moved = np.array([1, 1, 0, 0, 0, 1], bool)
    returning = np.array([1, 0, 0, 0, 0, 0], bool)
    relaying = np.array([0, 1, 1, 0, 0, 1], bool)
    alive = np.array([1, 1, 1, 1, 0, 0], bool)
    got = classify(moved, returning, relaying, alive).tolist()
    r = RobotState
    assert got == [r.RETURNING, r.MOVING, r.RELAYING, r.WAITING, r.FAILED, r.FAILED]


CASES = {
    "recurrent": {"name": "recurrent", "params": {"theta": 1, "check": True}},
    "recurrent-frontiers": {
        "name": "recurrent",
        "params": {"theta": 2, "relay_binding": "frontiers", "check": True},
    },
    "recurrent-failure": {
        "name": "recurrent",
        "params": {"theta": 1, "check": True, "failures": {"at_s": {1: 20.0}}},
    },
    "utility-greedy": {"name": "utility", "params": {"coordination": "greedy"}},
    "utility-none": {"name": "utility", "params": {"coordination": "none"}},
}


@pytest.mark.parametrize("case", list(CASES))
def test_summary_keys_agree_with_the_records(tmp_path, case: str) -> None:
    data = load_scenario("recurrent_demo").model_dump(mode="json")
    data["team"]["n_robots"] = 4
    data["sim"].update(max_steps=70, dt_s=2.0)  # 0.8 m per 2 s step; times in seconds
    data["strategy"] = CASES[case]
    data["output"].update(record_every=1, figures=False)
    s = run(scenario_from_dict(data, "demo.yaml"), out_dir=tmp_path, seed=1).summary
    fracs = [s[f"time_{name}_frac"] for name in SHARES]
    assert all(0.0 <= f <= 1.0 for f in fracs)
    assert sum(fracs) == pytest.approx(1.0, abs=1e-12)

    steps = pq.read_table(tmp_path / "steps.parquet").to_pydict()
    explored = np.asarray(steps["explored_fraction"])
    for pct in (50, 75, 90):
        hit = np.flatnonzero(explored >= pct / 100)
        want = None if len(hit) == 0 else float(steps["step"][hit[0]] * 2.0)
        assert s[f"time_to_{pct}pct_s"] == want

    robots = pq.read_table(tmp_path / "robots.parquet").to_pydict()
    step = np.asarray(robots["step"])
    state = np.asarray(robots["state"])[step > 0]
    live = state != RobotState.FAILED
    for code, name in enumerate(SHARES):
        assert s[f"time_{name}_frac"] == pytest.approx(np.mean(state[live] == code))
    n = s["n_robots"]
    out = (~np.asarray(robots["connected"], bool))[step > 0].reshape(-1, n)
    out &= live.reshape(-1, n)
    lengths = [le for r in range(n) for le in episodes(out[:, r])]
    assert s["out_of_comm_episodes"] == len(lengths)
    assert s["out_of_comm_longest_steps"] == max(lengths, default=0)
    assert s["out_of_comm_mean_steps"] == pytest.approx(sum(lengths) / n)

    if case.startswith("utility"):
        assert s["time_relaying_frac"] == 0.0
    if case == "recurrent":
        assert s["time_relaying_frac"] > 0  # theta = 1 holds relays
        assert s["constraint_violations"] == 0
    if case == "recurrent-failure":
        assert s["robots_failed"] == 1 and s["failures"] == [{"robot": 1, "step": 10}]
        assert (state.reshape(-1, n)[9:, 1] == RobotState.FAILED).all()
        assert (state.reshape(-1, n)[:9, 1] != RobotState.FAILED).all()
        assert s["constraint_violations"] == 0
