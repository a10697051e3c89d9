"""The single-agent (centralised) Gymnasium form: one controller commands the whole team."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from tether.envs.episode import Episode
from tether.envs.observe import OBS_LIMIT
from tether.envs.options import env_options


class TetherTeamEnv(gym.Env):
    """A scenario as one Gymnasium ``Env`` (see :func:`tether.envs.team_env`).

    The observation is every robot's observation, robot after robot
    (``(n * obs_size,)`` float32); the action every robot's velocity command, robot after
    robot (``Box(-1, 1, (n * dim,))``); the reward the team's. ``info["terms"]`` holds
    every reward term.
    """

    metadata = {"render_modes": []}

    def __init__(self, scenario: Any, **options: Any) -> None:
        self.episode = Episode(scenario, env_options(options))
        n, dim, size = self.episode.n, self.episode.dim, self.episode.obs_size
        self.observation_space = spaces.Box(-OBS_LIMIT, OBS_LIMIT, (n * size,), np.float32)
        self.action_space = spaces.Box(-1.0, 1.0, (n * dim,), np.float64)
        self._first = True

    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Start an episode of ``seed`` (default: the scenario's seed, then the next one)."""
        super().reset(seed=seed)
        obs = self.episode.reset(seed)
        return obs.reshape(-1), self._info()

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict[str, Any]]:
        a = np.asarray(action, dtype=float).reshape(self.episode.n, self.episode.dim)
        obs, reward, terminated, truncated = self.episode.step(a)
        return obs.reshape(-1), float(reward), terminated, truncated, self._info()

    def scripted_action(self) -> np.ndarray:
        """The scenario's own strategy's action for this step, ``(n * dim,)`` float64."""
        return self.episode.scripted_actions().reshape(-1)

    def _info(self) -> dict[str, Any]:
        rec = self.episode.records[-1]
        return {
            "terms": dict(self.episode.terms),
            "connected": bool(rec.connected),
            "lambda2": float(rec.lambda2),
        }

    def write_run(self, out_dir: Any, *, figures: bool | None = None) -> dict[str, Any]:
        """The episode as a run folder (``record=True``): see :meth:`Episode.write_run`."""
        return self.episode.write_run(out_dir, figures=figures)
