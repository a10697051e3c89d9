"""The training example's task and baseline stay what its page says (not its learning).

``examples/rl/train_leader_relay.py`` compares PPO with the ``silent`` strategy on
``leader_relay.yaml``; the page quotes the baseline as keeping the team connected and
finishing the leader's path. Training itself needs the ``rl`` extra and minutes, so the
suite runs the example end to end only when Stable-Baselines3 is installed, and then at
a size of seconds.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path
from types import ModuleType

import pytest

EXAMPLE = Path(__file__).parents[1] / "examples" / "rl" / "train_leader_relay.py"


def _example() -> ModuleType:
    spec = importlib.util.spec_from_file_location("tether_rl_example", EXAMPLE)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_the_scripted_baseline_keeps_the_relay_connected_to_the_path_end() -> None:
    ex = _example()
    seeds = [ex.EVAL_SEED0, ex.EVAL_SEED0 + 1]
    got = ex.evaluate(ex.scripted, seeds)
    assert got["always_connected"] == 1.0
    assert got["path_progress"] > 0.98
    assert got["steps"] < 100  # done before sim.max_steps
    assert got["collisions"] == 0.0


def test_random_actions_break_the_relay() -> None:
    """The task is not trivial: the same seeds under random actions disconnect."""
    import numpy as np

    ex = _example()
    rng = np.random.default_rng(0)

    def random(env, obs):  # noqa: ANN001, ANN202
        return rng.uniform(-1.0, 1.0, env.action_space.shape)

    got = ex.evaluate(random, [ex.EVAL_SEED0, ex.EVAL_SEED0 + 1])
    assert got["connected_steps"] < 0.8 and got["path_progress"] < 0.5


def test_the_example_trains_and_writes_its_curve(tmp_path: Path) -> None:
    pytest.importorskip("stable_baselines3")
    ex = _example()
    out = tmp_path / "rl"
    result = ex.main(
        ["--timesteps", "1024", "--evals", "1", "--eval-episodes", "1", "--n-envs", "2",
         "--out", str(out)]
    )  # fmt: skip
    assert [p["timesteps"] for p in result["learned"]][0] == 0
    assert result["learned"][-1]["timesteps"] >= 1024
    for name in ("curve.json", "curve.png", "learned_policy.zip", "episode/summary.json"):
        assert (out / name).exists(), name
