"""The papers' strategies through the environment reach what ``tether run`` reaches.

A scripted episode (the scenario's strategy acting through :class:`ScriptedPolicy`) of a
seed must be the run of ``tether run --seed``: the same summary numbers, the same tables.
The oracle is ``tether run`` itself (:func:`tether.runner.run`). An environment
episode, scripted or not, is written as a normal run folder that ``tether view`` and
``tether export`` read.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
from typer.testing import CliRunner

import tether.envs as te
from tether.cli import app
from tether.config import load_scenario
from tether.runner import run

#: summary keys that measure the machine, not the run
MACHINE_KEYS = {"wall_time_s", "cpu_time_s", "provenance", "timing_s"}

#: the three published strategies in their settings, shortened to seconds of test time
SETTINGS = [("silent_demo", 1, 60), ("connectivity_empty", 0, 40),
            ("multi_target_experiment", 0, 40)]  # fmt: skip


def shortened(name: str, steps: int) -> dict:
    data = load_scenario(name).model_dump(mode="json")
    data["sim"]["max_steps"] = steps
    data["output"]["figures"] = False
    return data


def scripted_episode(scenario: dict, seed: int, out: Path) -> tuple[dict, te.TetherParallelEnv]:
    env = te.parallel_env(scenario, record=True)
    policy = te.ScriptedPolicy(env)
    obs, _ = env.reset(seed=seed)
    while env.agents:
        obs, *_ = env.step(policy(obs))
    return env.write_run(out), env


@pytest.mark.parametrize(("name", "seed", "steps"), SETTINGS)
def test_scripted_episode_is_the_run_of_tether_run(
    name: str, seed: int, steps: int, tmp_path: Path
) -> None:
    scenario = shortened(name, steps)
    expected = run(scenario, out_dir=tmp_path / "run", seed=seed).summary
    got, env = scripted_episode(scenario, seed, tmp_path / "env")
    assert got["environment"]["policy"] == "scripted"
    assert got["environment"]["landing_misses"] == 0
    for key, value in expected.items():
        if key not in MACHINE_KEYS:
            assert got[key] == value, key
    for table in ("steps", "robots", "links", "events"):
        want = pq.read_table(tmp_path / "run" / f"{table}.parquet").to_pydict()
        have = pq.read_table(tmp_path / "env" / f"{table}.parquet").to_pydict()
        for column, values in want.items():  # NaN equals NaN here
            np.testing.assert_equal(have[column], values, err_msg=f"{table}.{column}")
    # the environment's rewards were measured on the same steps: one per step
    rewards = pq.read_table(tmp_path / "env" / "steps.parquet").to_pydict()["reward"]
    assert len(rewards) == expected["steps"] + 1
    assert sum(rewards[1:]) == pytest.approx(got["environment"]["episode_return"])


def test_a_learned_policy_and_the_baseline_share_the_seed() -> None:
    scenario = shortened("silent_demo", 5)
    env = te.parallel_env(scenario)
    env.reset(seed=3)
    start = env.episode.state.positions.copy()
    random = te.run_episode(env, te.random_policy(env, seed=0), seed=3)
    scripted = te.run_episode(env, te.ScriptedPolicy(env), seed=3)
    env.reset(seed=3)
    np.testing.assert_array_equal(env.episode.state.positions, start)
    assert random["policy"] == "actions" and scripted["policy"] == "scripted"
    assert random["steps"] == scripted["steps"] == 5


def test_an_episode_is_a_run_folder_that_view_and_export_read(tmp_path: Path) -> None:
    scenario = shortened("recurrent_demo", 6)
    scenario["output"]["record_every"] = 1
    env = te.parallel_env(scenario, record=True)
    te.run_episode(env, te.random_policy(env, seed=1), seed=0)
    summary = env.write_run(tmp_path / "episode")
    assert summary["steps"] == 6 and summary["environment"]["policy"] == "actions"
    assert "task_explored_fraction" in summary["environment"]
    robots = pq.read_table(tmp_path / "episode" / "robots.parquet").to_pydict()
    last = np.array(robots["step"]) == 6
    xy = np.column_stack([robots["x_m"], robots["y_m"]])[last]
    np.testing.assert_allclose(
        xy[np.argsort(np.array(robots["robot"])[last])], env.episode.state.positions
    )
    runner = CliRunner()
    view = runner.invoke(app, ["view", str(tmp_path / "episode")])
    assert view.exit_code == 0, view.output
    assert (tmp_path / "episode" / "replay.html").stat().st_size > 10_000
    export = runner.invoke(app, ["export", str(tmp_path / "episode"), "--format", "mcap"])
    assert export.exit_code == 0, export.output
    assert list((tmp_path / "episode").glob("*.mcap"))


def test_writing_needs_record_and_never_overwrites_a_foreign_folder(tmp_path: Path) -> None:
    env = te.parallel_env(shortened("silent_demo", 3))
    te.run_episode(env, te.random_policy(env), seed=0)
    with pytest.raises(RuntimeError, match="record=True"):
        env.write_run(tmp_path / "x")
    env = te.parallel_env(shortened("silent_demo", 3), record=True)
    te.run_episode(env, te.random_policy(env), seed=0)
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "notes.txt").write_text("keep me")
    with pytest.raises(Exception, match="not a tether run folder|not empty"):
        env.write_run(mine)
    assert (mine / "notes.txt").read_text() == "keep me"
