"""The PettingZoo ``ParallelEnv`` of a scenario: one agent per robot, all acting at once."""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from tether.envs.episode import Episode
from tether.envs.observe import OBS_LIMIT
from tether.envs.options import env_options


class TetherParallelEnv(ParallelEnv):
    """A scenario as a PettingZoo ``ParallelEnv`` (see :func:`tether.envs.parallel_env`).

    Agents are ``robot_0 .. robot_{n-1}``; an action is a robot's velocity as a fraction
    of its speed bound (``Box(-1, 1, (dim,))``); an observation is the vector of
    :mod:`tether.envs.observe`. Every agent gets the team's reward; ``infos[agent]``
    holds every reward term (``terms``) and the step's connectivity (``connected``,
    ``lambda2``). All agents end together: on the task's completion (terminated) or at
    ``sim.max_steps`` (truncated).
    """

    metadata = {"name": "tether_v0", "render_modes": [], "is_parallelizable": True}

    def __init__(self, scenario: Any, **options: Any) -> None:
        self.episode = Episode(scenario, env_options(options))
        n, dim = self.episode.n, self.episode.dim
        self.possible_agents = [f"robot_{i}" for i in range(n)]
        self.agents: list[str] = []
        self.render_mode = None
        self._obs_space = spaces.Box(-OBS_LIMIT, OBS_LIMIT, (self.episode.obs_size,), np.float32)
        self._act_space = spaces.Box(-1.0, 1.0, (dim,), np.float64)

    @property
    def scenario_name(self) -> str:
        return self.episode.scenario.name

    @cache  # noqa: B019 (one space object per agent, as PettingZoo asks)
    def observation_space(self, agent: str) -> spaces.Box:
        return self._obs_space

    @cache  # noqa: B019
    def action_space(self, agent: str) -> spaces.Box:
        return self._act_space

    def reset(
        self, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, np.ndarray], dict[str, dict[str, Any]]]:
        """Start an episode of ``seed`` (default: the scenario's seed, then the next one)."""
        obs = self.episode.reset(seed)
        self.agents = list(self.possible_agents)
        info = self._info()
        return (
            {a: obs[i] for i, a in enumerate(self.agents)},
            {a: dict(info) for a in self.agents},
        )

    def step(self, actions: dict[str, Any]) -> tuple[dict, dict, dict, dict, dict]:
        """One step of ``sim.dt_s`` with every live agent's action."""
        if not self.agents:
            raise RuntimeError("the episode is over; call reset() first")
        missing = [a for a in self.agents if a not in actions]
        if missing:
            raise ValueError(f"actions: no action for {missing[0]} (every agent acts each step)")
        a = np.stack(
            [np.asarray(actions[name], dtype=float).reshape(-1) for name in self.possible_agents]
        )
        obs, reward, terminated, truncated = self.episode.step(a)
        agents = self.agents
        info = self._info()
        out = (
            {a: obs[i] for i, a in enumerate(agents)},
            dict.fromkeys(agents, reward),
            dict.fromkeys(agents, terminated),
            dict.fromkeys(agents, truncated),
            {a: dict(info) for a in agents},
        )
        if terminated or truncated:
            self.agents = []
        return out

    def scripted_actions(self) -> dict[str, np.ndarray]:
        """The scenario's own strategy's actions for this step (:class:`ScriptedPolicy`)."""
        a = self.episode.scripted_actions()
        return {name: a[i] for i, name in enumerate(self.possible_agents)}

    def _info(self) -> dict[str, Any]:
        rec = self.episode.records[-1]
        return {
            "terms": dict(self.episode.terms),
            "connected": bool(rec.connected),
            "lambda2": float(rec.lambda2),
            "step": int(rec.step),
        }

    def state(self) -> np.ndarray:
        """Every robot's observation, stacked (``(n * obs_size,)``): a critic's input."""
        return self.episode.observe().reshape(-1)

    def write_run(self, out_dir: Any, *, figures: bool | None = None) -> dict[str, Any]:
        """The episode as a run folder (``record=True``): see :meth:`Episode.write_run`."""
        return self.episode.write_run(out_dir, figures=figures)

    def render(self) -> None:
        """No live rendering: record the episode and view its run folder (``tether view``)."""
        return None

    def close(self) -> None:
        return None
