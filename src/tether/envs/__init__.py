"""Scenarios as reinforcement-learning environments (PettingZoo and Gymnasium).

Any scenario -- a YAML path or a built-in name -- becomes an environment whose episodes
start exactly where ``tether run --seed`` starts::

    import tether.envs

    env = tether.envs.parallel_env("silent_demo")        # PettingZoo ParallelEnv
    obs, infos = env.reset(seed=1)
    policy = tether.envs.ScriptedPolicy(env)               # the paper's controller
    while env.agents:
        obs, rewards, terminated, truncated, infos = env.step(policy(obs))

* :func:`parallel_env` -- PettingZoo ``ParallelEnv``, one agent per robot (:func:`env`:
  its AEC form);
* :func:`team_env` -- one Gymnasium ``Env`` commanding the whole team (centralised);
* :func:`vector_env` -- a Gymnasium ``VectorEnv`` stepping many copies in one compiled
  call per step (links and lambda2 of every copy included);
* :class:`ScriptedPolicy` -- the scenario's strategy (``silent``, ``connectivity``,
  ``multi_target``) as a policy on the same interface.

Observations, actions, reward terms and options: docs/how-to/environments.md. Needs
``pip install "tether[envs]"`` (PettingZoo and Gymnasium).
"""

from __future__ import annotations

from typing import Any

try:
    import gymnasium  # noqa: F401
    import pettingzoo  # noqa: F401
    from pettingzoo.utils.conversions import parallel_to_aec
except ImportError as exc:  # pragma: no cover - depends on the installation
    raise ImportError(
        f"tether.envs needs PettingZoo and Gymnasium ({exc.name} is missing): "
        'pip install "tether[envs]"'
    ) from None

from tether.envs.options import DEFAULT_WEIGHTS, TERMS, EnvOptions
from tether.envs.parallel import TetherParallelEnv
from tether.envs.scripted import ScriptedPolicy, random_policy, run_episode
from tether.envs.single import TetherTeamEnv


def parallel_env(scenario: Any, **options: Any) -> TetherParallelEnv:
    """A PettingZoo ``ParallelEnv`` of ``scenario`` (a YAML path, a built-in name, a
    :class:`tether.config.Scenario` or a dict); ``options`` as in docs/how-to/environments.md
    (``reward={...}``, ``max_neighbours``, ``map_patch_cells``, ``max_speed_mps``,
    ``clearance_m``, ``coverage_cell_m``, ``record``)."""
    return TetherParallelEnv(scenario, **options)


def env(scenario: Any, **options: Any) -> Any:
    """The AEC form of :func:`parallel_env` (PettingZoo's conversion)."""
    return parallel_to_aec(parallel_env(scenario, **options))


def team_env(scenario: Any, **options: Any) -> TetherTeamEnv:
    """A single-agent Gymnasium ``Env`` of ``scenario``: one action for the whole team."""
    return TetherTeamEnv(scenario, **options)


def vector_env(scenario: Any, num_envs: int, **options: Any) -> Any:
    """A Gymnasium ``VectorEnv`` of ``num_envs`` copies of ``scenario`` stepped together."""
    from tether.envs.vector import TetherVectorEnv

    return TetherVectorEnv(scenario, num_envs, **options)


__all__ = [
    "DEFAULT_WEIGHTS",
    "TERMS",
    "EnvOptions",
    "ScriptedPolicy",
    "TetherParallelEnv",
    "TetherTeamEnv",
    "env",
    "parallel_env",
    "random_policy",
    "run_episode",
    "team_env",
    "vector_env",
]
