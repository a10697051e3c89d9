"""The vector form (one compiled call for every copy) against the parallel form, its reference.

For a noise-free scenario, copy ``e`` of ``vector_env(...).reset(seed=s)`` is the episode
of ``parallel_env(...).reset(seed=s + e)``: the same start, and for the same actions the
same observations, rewards and terms (the parallel form computes them with numpy, scipy
and the core loop's metrics: an independent implementation). Then the vector form's own
contract: next-step autoreset with the next seeds, Gymnasium's spaces, clear errors.
"""

from __future__ import annotations

import numpy as np
import pytest

import tether.envs as te
from tether.config import load_scenario
from tether.envs.options import TERMS
from tether.graph import is_connected
from tether.runner import build
from tether.sensing import sensed_pairs

pytestmark = pytest.mark.timeout(900)  # the first call compiles the kernels (cold cache)


def noise_free(name: str, steps: int | None = None) -> dict:
    data = load_scenario(name).model_dump(mode="json")
    data["sensing"]["noise"] = "none"
    if steps is not None:
        data["sim"]["max_steps"] = steps
    return data


@pytest.mark.parametrize(
    ("name", "options"),
    [
        ("silent_demo", {}),  # free plane, occlusion by bodies, leader path
        ("connectivity_empty", {"map_patch_cells": 1}),  # 3-D box, operator goal
        ("multi_target_experiment", {"map_patch_cells": 1}),  # office walls, targets
    ],
)
def test_each_copy_is_the_parallel_episode_of_its_seed(name: str, options: dict) -> None:
    scenario = noise_free(name)
    copies, seed, steps = 3, 4, 8
    venv = te.vector_env(scenario, copies, **options)
    obs, _ = venv.reset(seed=seed)
    rng = np.random.default_rng(0)
    actions = rng.uniform(-1.2, 1.2, (steps, *venv.action_space.shape))
    for e in range(copies):
        env = te.parallel_env(scenario, **options)
        first, _ = env.reset(seed=seed + e)
        np.testing.assert_array_equal(env.episode.state.positions, venv.positions[e])
        np.testing.assert_allclose(obs[e], np.stack(list(first.values())), atol=1e-6)
    got = []
    for k in range(steps):
        obs, rewards, terminated, truncated, infos = venv.step(actions[k])
        got.append((obs.copy(), rewards.copy(), infos["terms"].copy(), venv.positions.copy()))
    for e in range(copies):
        env = te.parallel_env(scenario, **options)
        env.reset(seed=seed + e)
        for k in range(steps):
            o, r, _, _, info = env.step({a: actions[k, e, i] for i, a in enumerate(env.agents)})
            v_obs, v_rew, v_terms, v_pos = (x[e] for x in got[k])
            np.testing.assert_array_equal(env.episode.state.positions, v_pos)
            np.testing.assert_allclose(v_obs, np.stack(list(o.values())), atol=1e-6)
            want = info["robot_0"]["terms"]
            np.testing.assert_allclose(
                v_terms[:8], [want[t] for t in TERMS][:8], rtol=1e-9, atol=1e-9
            )
            assert v_terms[8] == want["blocked"]
            assert v_rew == pytest.approx(r["robot_0"], rel=1e-9, abs=1e-9)


def test_copies_restart_on_the_next_step_with_the_next_seed() -> None:
    scenario = noise_free("silent_demo", steps=3)
    venv = te.vector_env(scenario, 2)
    venv.reset(seed=10)
    zero = np.zeros(venv.action_space.shape)
    for k in range(3):
        _, _, terminated, truncated, _ = venv.step(zero)
        assert not terminated.any()
        assert truncated.all() == (k == 2)
    obs, rewards, terminated, truncated, _ = venv.step(zero + 1.0)  # ignored: copies restart
    assert not truncated.any() and (rewards == 0).all()
    for e in range(2):
        np.testing.assert_array_equal(venv.positions[e], build(scenario, 12 + e).initial.positions)


def test_vector_spaces_and_errors() -> None:
    venv = te.vector_env("connectivity_empty", 5, max_neighbours=2)
    n, dim = 8, 3
    assert venv.single_action_space.shape == (n, dim)
    assert venv.observation_space.shape == (5, n, 3 * dim + 1 + 2 * (dim + 2))
    obs, _ = venv.reset(seed=0)
    assert obs.dtype == np.float32 and venv.observation_space.contains(obs)
    with pytest.raises(ValueError, match=r"shape \(5, 8, 3\)"):
        venv.step(np.zeros((5, 8, 2)))
    with pytest.raises(ValueError, match="finite"):
        venv.step(np.full((5, 8, 3), np.inf))
    with pytest.raises(ValueError, match="num_envs"):
        te.vector_env("connectivity_empty", 0)
    with pytest.raises(ValueError, match="no vector form"):
        te.vector_env("recurrent_demo", 2)


@pytest.mark.parametrize("n", [2, 3])
def test_lambda2_of_two_and_three_robots_is_the_laplacians(n: int) -> None:
    """Teams of 2 and 3 robots take lambda2 from the path's and the triangle's spectra."""
    data = noise_free("silent_demo")
    data["team"]["n_robots"] = n
    copies = 64
    venv = te.vector_env(data, copies)
    venv.reset(seed=0)
    built = build(data, 0)
    rng = np.random.default_rng(1)
    lam = list(TERMS).index("lambda2")
    seen = set()
    for _ in range(6):  # small random moves: teams that are paths or triangles
        *_, infos = venv.step(rng.uniform(-0.1, 0.1, venv.action_space.shape))
        for e in range(copies):
            pairs = sensed_pairs(venv.positions[e], built.sensor, built.world)
            lap = np.zeros((n, n))
            for i, j in pairs:
                lap[[i, j], [j, i]] -= 1.0
                lap[[i, j], [i, j]] += 1.0
            linked = is_connected(n, pairs)
            want = max(np.linalg.eigvalsh(lap)[1], 0.0) if linked else 0.0
            assert infos["terms"][e, lam] == pytest.approx(want, abs=1e-12)
            seen.add((linked, len(pairs)))
    assert (True, n - 1) in seen  # one link, or the path of three
    assert n == 2 or (True, 3) in seen  # the triangle
