"""The targets a run used are in its folder, and every viewer shows them from there.

The oracle is the scenario itself: a ``schedule`` of targets with known positions and
appearance times, and the run's own ``target_reached`` events for when each is done.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from tether.config import scenario_from_dict
from tether.runner import run
from tether.targets_recorded import FINISHED, HIDDEN, OPEN, recorded_targets
from tether.viewing.runfolder import load_run

TARGETS = [  # robot, position, appears at (s)
    (0, [13.0, 10.0, 4.0], 0.0),
    (1, [7.0, 10.0, 4.0], 0.0),
    (0, [13.0, 13.0, 4.0], 6.0),
]


def scenario() -> dict:
    return {
        "name": "mt-schedule",
        "seed": 2,
        "world": {"scene": "empty", "dim": 3,
                  "params": {"size_m": [20.0, 20.0], "height_m": 8.0, "resolution_m": 0.5}},
        "team": {"n_robots": 5},
        "sensing": {"range_m": 6.0, "occlusion": False, "noise": "none"},
        "sim": {"dt_s": 0.1, "max_steps": 400, "collision_distance_m": 1.0},
        "strategy": {"name": "multi_target", "params": {
            "preset": "outdoor",
            "targets": {"kind": "schedule", "params": {"targets": [
                {"robot": r, "position_m": p, "at_s": t, "stay_s": 1.0} for r, p, t in TARGETS]}},
            "start": {"center_m": [10.0, 10.0, 4.0]}}},
        "output": {"record_every": 2, "figures": True},
    }  # fmt: skip


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("targets") / "run"
    run(scenario_from_dict(scenario(), "schedule.yaml"), out_dir=path)
    return path


def _reached(run_dir: Path) -> dict[int, int]:
    events = pq.read_table(run_dir / "events.parquet").to_pylist()
    return {e["target"]: e["step"] for e in events if e["kind"] == "target_reached"}


def test_the_run_folder_holds_the_targets_the_scenario_gave(run_dir: Path) -> None:
    data = load_run(run_dir)
    assert data.targets is not None
    got = sorted(zip(data.targets.robots.tolist(), data.targets_m.tolist(),
                     data.targets.appear_s.tolist(), strict=True))  # fmt: skip
    assert got == sorted(TARGETS)
    reached = _reached(run_dir)
    assert reached, "no target reached in the run: the test would check nothing"
    assert sorted(data.targets.ids.tolist()) == [0, 1, 2]
    for ident, step in reached.items():
        assert data.targets.finished_steps[data.targets.ids.tolist().index(ident)] == step


def test_target_states_follow_appearance_and_arrival(run_dir: Path) -> None:
    data = load_run(run_dir, world=False)
    marks = data.targets
    late = int(np.argmax(marks.appear_s))  # the target that appears at 6 s
    assert marks.states(0, 0.0).tolist() == [HIDDEN if k == late else OPEN for k in range(3)]
    assert marks.states(59, 5.9)[late] == HIDDEN
    assert marks.states(60, 6.0)[late] != HIDDEN
    step, ident = min((s, t) for t, s in _reached(run_dir).items())
    target = marks.ids.tolist().index(ident)
    assert marks.states(step - 1, (step - 1) * 0.1)[target] == OPEN
    assert marks.states(step, step * 0.1)[target] == FINISHED
    frames = marks.first_frames(data.frame_steps, data.frame_times_s)
    for k in range(len(marks)):
        shown = [marks.states(s, t)[k] != HIDDEN for s, t in zip(
            data.frame_steps, data.frame_times_s, strict=True)]  # fmt: skip
        assert frames[k, 0] == (shown.index(True) if any(shown) else -1)


def test_the_animation_draws_only_the_targets_shown_at_each_frame(run_dir: Path) -> None:
    from tether.viewing.animate import _Painter

    data = load_run(run_dir)
    painter = _Painter(data, 6.0, 60)
    try:
        shown = np.arange(data.n_frames)
        for k in (0, data.n_frames - 1):
            painter.draw(k, shown)
            states = data.targets.states(int(data.frame_steps[k]), float(data.frame_times_s[k]))
            offsets = np.asarray(painter.target_dots.get_offsets())
            np.testing.assert_allclose(offsets, data.targets_m[states != HIDDEN, :2])
            faces = painter.target_dots.get_facecolors()
            assert sum(f[3] == 0 for f in faces) == int(np.sum(states == FINISHED))
    finally:
        painter.close()


def test_the_snapshot_and_summary_are_written(run_dir: Path) -> None:
    assert (run_dir / "figures" / "snapshot.png").stat().st_size > 10_000
    summary = json.loads((run_dir / "summary.json").read_text())
    assert summary["targets_total"] == len(TARGETS)


def test_recorded_targets_reads_what_parquet_stores() -> None:
    events = [
        {"step": 0, "kind": "target_added", "robot": 1, "target": 7, "position_m": "[1, 2]"},
        {"step": 0, "kind": "target_added", "robot": 2, "target": 8, "position_m": None},
        {"step": 3, "kind": "target_added", "robot": 0, "target": 9, "position_m": [4.0, 5.0, 6.0]},
        {"step": 5, "kind": "target_dropped", "robot": 0, "target": 9},
        {"step": 6, "kind": "role", "robot": 0},
    ]
    marks = recorded_targets(events, 3)
    assert marks.positions_m.tolist() == [[1.0, 2.0, 0.0], [4.0, 5.0, 6.0]]
    assert marks.finished_steps.tolist() == [-1, 5]
    assert marks.states(2, 0.2).tolist() == [OPEN, HIDDEN]
    assert marks.states(5, 0.5).tolist() == [OPEN, FINISHED]
    assert recorded_targets([{"kind": "role", "step": 0}], 2) is None
