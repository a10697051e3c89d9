"""The environments keep PettingZoo's and Gymnasium's contracts, for every scenario kind.

PettingZoo's own API and seed tests run on one built-in scenario of each kind (the
strategies' settings: leader path, continuous connectivity, targets, exploration with a
base station); Gymnasium's env checker on the single-agent form. Then what a user relies
on beyond the contracts: the spaces the docs give, bounded moves, connectivity measured
and never enforced, seeds that reproduce ``tether run``'s start, clear errors.
"""

from __future__ import annotations

import re
import warnings
from pathlib import Path

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from pettingzoo.test import api_test, parallel_api_test, parallel_seed_test, seed_test

import tether.envs as te
from tether.runner import build

#: one built-in scenario of each kind (docs/how-to/environments.md, "Scenario kinds")
KINDS = {
    "leader": "silent_demo",
    "continuous": "connectivity_empty",
    "targets": "multi_target_experiment",
    "exploration": "recurrent_demo",
    "exploration (utility)": "recurrent_utility",
}


@pytest.mark.parametrize("kind", list(KINDS))
def test_pettingzoo_parallel_api_and_seed(kind: str) -> None:
    name = KINDS[kind]
    env = te.parallel_env(name)
    assert env.episode.setting.kind == kind.split()[0]
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # PettingZoo reports contract slips as warnings
        parallel_api_test(env, num_cycles=12)
        parallel_seed_test(lambda: te.parallel_env(name), num_cycles=12)


@pytest.mark.parametrize("kind", list(KINDS))
def test_pettingzoo_aec_api_and_seed(kind: str) -> None:
    name = KINDS[kind]
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        api_test(te.env(name), num_cycles=12)
        seed_test(lambda: te.env(name), num_cycles=12)


@pytest.mark.parametrize("kind", list(KINDS))
def test_gymnasium_env_checker_passes_for_the_team_form(kind: str) -> None:
    env = te.team_env(KINDS[kind], max_neighbours=3)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env, skip_render_check=True)
    n, dim = env.episode.n, env.episode.dim
    assert env.action_space.shape == (n * dim,)
    assert env.observation_space.shape == (n * (3 * dim + 1 + 3 * (dim + 2)),)


def test_spaces_follow_the_documented_layout() -> None:
    env = te.parallel_env("connectivity_empty", max_neighbours=4, map_patch_cells=1)
    dim = 3
    size = 3 * dim + 1 + 4 * (dim + 2) + 3**dim
    assert env.observation_space("robot_0").shape == (size,)
    assert env.action_space("robot_0").shape == (dim,)
    obs, _ = env.reset(seed=0)
    q = env.episode.state.positions
    o = obs["robot_0"]
    # own position from the start centroid, over the link range (Rs = 6 m outdoors)
    np.testing.assert_allclose(o[dim : 2 * dim], (q[0] - q.mean(axis=0)) / 6.0, rtol=1e-6)
    # robot 0 has the operator's goal: its task vector and flag
    goal = np.array([40.0, 50.0, 4.0])
    np.testing.assert_allclose(o[2 * dim : 3 * dim], (goal - q[0]) / 6.0, rtol=1e-6)
    assert o[3 * dim] == 1.0 and obs["robot_1"][3 * dim] == 0.0
    # the first neighbour slot is the nearest sensed robot, with its margin
    slot = o[3 * dim + 1 : 3 * dim + 1 + dim + 2]
    d = np.linalg.norm(q[1:] - q[0], axis=1)
    k = int(np.argmin(d)) + 1
    np.testing.assert_allclose(slot[:dim], (q[k] - q[0]) / 6.0, rtol=1e-6)
    assert slot[dim] == pytest.approx(1 - d.min() / 6.0, rel=1e-6) and slot[dim + 1] == 1.0


def test_episode_starts_where_tether_run_starts() -> None:
    env = te.parallel_env("silent_demo")
    env.reset(seed=5)
    np.testing.assert_array_equal(
        env.episode.state.positions, build("silent_demo", 5).initial.positions
    )


def test_moves_are_bounded_by_the_robot_speed() -> None:
    env = te.parallel_env("multi_target_experiment")
    env.reset(seed=0)
    q0 = env.episode.state.positions.copy()
    bound = env.episode.setting.max_speed_mps * env.episode.setting.dt_s
    assert env.episode.setting.max_speed_mps == pytest.approx(1.0)  # experiment preset: 2 v_cruise
    env.step({a: np.array([30.0, -40.0, 0.0]) for a in env.agents})  # norm 50: scaled to 1
    moved = np.linalg.norm(env.episode.state.positions - q0, axis=1)
    assert moved.max() <= bound * (1 + 1e-9)
    assert moved.max() > 0.5 * bound


def test_walls_stop_moves_and_are_counted() -> None:
    env = te.parallel_env("recurrent_demo")
    env.reset(seed=0)
    world = env.episode.built.world
    for _ in range(40):  # everyone drives west into the map's edge and walls
        _, _, _, _, infos = env.step({a: np.array([-1.0, 0.0]) for a in env.agents})
    q = env.episode.state.positions
    assert world.points_free(q).all()
    assert infos["robot_0"]["terms"]["blocked"] >= 1


def test_connectivity_is_measured_not_enforced() -> None:
    env = te.parallel_env(
        "silent_demo", reward={"disconnected": -5.0, "progress": 0.0, "margin": 0.0, "blocked": 0.0}
    )
    env.reset(seed=1)
    n = env.episode.n
    directions = np.array([[np.cos(a), np.sin(a)] for a in np.linspace(0, 2 * np.pi, n + 1)[:n]])
    for _ in range(3):  # everyone flies outwards at full speed: the team falls apart
        _, rewards, _, _, infos = env.step({f"robot_{i}": directions[i] for i in range(n)})
    info = infos["robot_0"]
    assert info["connected"] is False and info["terms"]["disconnected"] == 1.0
    assert rewards["robot_0"] == pytest.approx(-5.0 + -1.0 * info["terms"]["collisions"])


def test_truncation_at_max_steps() -> None:
    env = te.parallel_env(
        {
            "name": "tiny",
            "team": {"n_robots": 3, "init": {"kind": "grid", "spacing_m": 2.0}},
            "sensing": {"range_m": 5.0},
            "sim": {"dt_s": 1.0, "max_steps": 4},
            "strategy": {
                "name": "silent",
                "params": {"trajectory": {"waypoints": [[0, 0], [50, 0]]}},
            },
        }
    )
    env.reset(seed=0)
    for step in range(4):
        _, _, term, trunc, _ = env.step({a: np.zeros(2) for a in env.agents})
        assert not any(term.values())
        assert all(trunc.values()) == (step == 3)
    assert env.agents == []
    with pytest.raises(RuntimeError, match="reset"):
        env.step({})


def test_bad_options_and_actions_are_one_line_errors() -> None:
    with pytest.raises(TypeError, match="max_neighbors.*did you mean 'max_neighbours'"):
        te.parallel_env("silent_demo", max_neighbors=3)
    with pytest.raises(ValueError, match="unknown reward term 'lamda2'.*'lambda2'"):
        te.parallel_env("silent_demo", reward={"lamda2": 1.0})
    with pytest.raises(ValueError, match="max_neighbours"):
        te.parallel_env("silent_demo", max_neighbours=-1)
    env = te.parallel_env("silent_demo")
    env.reset(seed=0)
    with pytest.raises(ValueError, match="no action for robot_1"):
        env.step({"robot_0": np.zeros(2)})
    with pytest.raises(ValueError, match="finite"):
        env.step({a: np.array([np.nan, 0.0]) for a in env.agents})
    with pytest.raises(RuntimeError, match="other actions were taken"):
        env.step({a: np.zeros(2) for a in env.agents})
        env.scripted_actions()


def test_the_docs_give_every_term_its_default_weight_and_every_option() -> None:
    page = (Path(__file__).parents[1] / "docs/how-to/environments.md").read_text()
    for name, weight in te.DEFAULT_WEIGHTS.items():
        row = re.search(rf"^\| `{name}` \| (.*) \| (\S+) \|$", page, re.MULTILINE)
        assert row is not None, f"docs: no row for the reward term {name}"
        assert float(row.group(2)) == weight, name
    assert set(te.DEFAULT_WEIGHTS) == set(te.TERMS)
    for option in te.EnvOptions.model_fields:
        assert f"| `{option}` |" in page, f"docs: option {option} is not documented"
