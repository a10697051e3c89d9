"""The papers' strategies as policies on the environments' interface.

A :class:`ScriptedPolicy` answers an environment's observations with the actions of the
scenario's own strategy (``silent``, ``connectivity``, ``multi_target``): the strategy
moves the team from the environment's state exactly as in ``tether run`` and the actions
land every robot where it moved. So a learned policy and the paper's controller run on
the same seeds, are scored by the same reward terms, and the scripted episode is the run
``tether run --seed`` makes (tests/test_envs_scripted.py compares their summaries).

The strategy sees the whole team's state (it is the team-level simulation of each robot's
own controller), which is why it acts through the environment rather than from one
agent's observation.
"""

from __future__ import annotations

from typing import Any

import numpy as np


class ScriptedPolicy:
    """The scenario's own strategy as a policy of a parallel or single-agent environment."""

    def __init__(self, env: Any) -> None:
        if not hasattr(env, "episode"):
            raise TypeError(
                "ScriptedPolicy needs a tether environment (tether.envs.parallel_env or "
                f"team_env), got {type(env).__name__}"
            )
        self.env = env

    def __call__(self, observations: Any = None) -> Any:
        """The actions for the current step (a dict per agent, or one array)."""
        if hasattr(self.env, "scripted_actions"):
            return self.env.scripted_actions()
        return self.env.scripted_action()


def run_episode(env: Any, policy: Any, seed: int | None = None) -> dict[str, Any]:
    """Run one episode of a parallel environment with ``policy(observations) -> actions``.

    Returns the episode's summary keys (:meth:`tether.envs.episode.Episode.metrics`) and
    its length.
    """
    obs, _ = env.reset(seed=seed)
    while env.agents:
        obs, *_ = env.step(policy(obs))
    out = env.episode.metrics()
    out["steps"] = env.episode.step_count
    out["connected_all_steps"] = bool(all(r.connected for r in env.episode.records))
    return out


def random_policy(env: Any, seed: int = 0) -> Any:
    """A policy of uniformly random actions (seeded), for baselines and tests."""
    rng = np.random.default_rng(seed)
    shape = env.action_space(env.possible_agents[0]).shape

    def act(observations: Any) -> dict[str, np.ndarray]:
        return {a: rng.uniform(-1.0, 1.0, shape) for a in env.agents}

    return act
