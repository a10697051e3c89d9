"""The Gymnasium vector form: many copies of a team stepped in one compiled call per step.

``tether.envs.vector_env(scenario, num_envs)`` is a ``gymnasium.vector.VectorEnv`` whose
copies are the single-agent (centralised) form of :func:`tether.envs.team_env`:
observations ``(num_envs, n, obs_size)`` float32, actions ``(num_envs, n, dim)`` in
``[-1, 1]``, one team reward per copy, and ``infos["terms"]`` ``(num_envs, 10)`` (the
terms in the order of :data:`tether.envs.options.TERMS`). A step of every copy is one
call of :func:`tether.envs.vector_kernels.step_all`.

What the copies share and what they do not:

* every copy runs in the world built for the scenario's seed, on the scenario's path,
  goals or targets; its team is placed as ``tether run --seed`` places it, copy ``e`` of
  ``reset(seed=s)`` with seed ``s + e`` (a copy that ends starts again with its seed plus
  ``num_envs``, on the next step: Gymnasium's next-step autoreset);
* sensing is noise-free (the measured relative positions are the true ones); range, line
  of sight and occlusion by robot bodies are as in the other forms;
* the ``clearance`` term is not computed (always 0); exploration scenarios (coverage of a
  map) have no vector form.

With a noise-free scenario a copy and :func:`tether.envs.parallel_env` give the same
observations and rewards for the same actions (``tests/test_envs_vector.py``).
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv

from tether.envs.episode import Episode
from tether.envs.observe import OBS_LIMIT
from tether.envs.options import TERMS, env_options
from tether.envs.tasks import Goals, LeaderPath, Targets
from tether.envs.vector_start import place, start_plan, world_tuple
from tether.paths.trajectory import Polyline
from tether.runner import check_seed, place_team
from tether.sim import TeamState


def world_arrays(world: Any) -> tuple:
    """The world tuple of :mod:`tether.envs.vector_world` for the step kernels."""
    return world_tuple(world, keep_grid=False)


def task_arrays(task: Any, copies: int, n: int, dim: int, dt_s: float) -> tuple:
    """The task tuple of :mod:`tether.envs.vector_tasks` (state arrays zeroed)."""
    kind = 0
    path = (
        np.zeros((1, dim)),
        np.zeros((0, dim)),
        np.zeros(0),
        np.zeros(1),
        np.zeros(0),
        0.0,
        np.zeros(dim),
        0.0,
        0.0,
        0.0,
    )
    goals = (np.zeros(0, np.int64), np.zeros((0, dim)), np.zeros((copies, 0)))
    targets = (np.zeros((n, 0, dim)), np.zeros((n, 0)), np.zeros((n, 0)), np.zeros(n, np.int64))
    rz, total = 0.0, 0
    if isinstance(task, LeaderPath):
        traj = task.trajectory
        if not isinstance(traj, Polyline):
            raise ValueError("the vector form follows waypoint paths only (not a function of time)")
        kind = 1
        path = (
            traj.waypoints,
            traj._seg,
            np.asarray(traj._denom, float),
            traj._cum,
            traj._seg_len,
            traj.length_m,
            traj.end,
            task.carrot_m,
            task.window_m,
            task.goal_tolerance_m,
        )
    elif isinstance(task, Goals):
        kind = 2
        goals = (task.robots.astype(np.int64), task.goals, np.zeros((copies, len(task.robots))))
    elif isinstance(task, Targets):
        kind = 3
        longest = max((len(q) for q in task.queues), default=0)
        tq, stay, appear = (
            np.zeros((n, longest, dim)),
            np.zeros((n, longest)),
            np.zeros((n, longest)),
        )
        for r, queue in enumerate(task.queues):
            for k, (pos, s, a) in enumerate(queue):
                tq[r, k], stay[r, k], appear[r, k] = pos, s, a
        count = np.array([len(q) for q in task.queues], np.int64)
        targets = (tq, stay, appear, count)
        rz, total = task.rz_m, task.total
    return (
        kind,
        np.zeros(copies, np.int64),
        np.zeros(copies),
        *path,
        np.zeros((copies, dim)),
        *goals,
        *targets,
        np.zeros((copies, n), np.int64),
        np.zeros((copies, n)),
        np.zeros(copies, np.int64),
        float(rz),
        float(dt_s),
        int(total),
    )


class TetherVectorEnv(VectorEnv):
    """``num_envs`` copies of a scenario's team (see the module docstring)."""

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP}

    def __init__(self, scenario: Any, num_envs: int, **options: Any) -> None:
        if isinstance(num_envs, bool) or not isinstance(num_envs, int) or num_envs < 1:
            raise ValueError(f"num_envs must be a positive integer (got {num_envs!r})")
        opts = env_options(options)
        if opts.record:
            raise ValueError("the vector form records nothing; record episodes of parallel_env")
        self.template = ep = Episode(scenario, opts)
        s = ep.setting
        if s.kind == "exploration":
            raise ValueError(
                f"{ep.scenario.name}: exploration scenarios have no vector form (coverage of "
                "the map is not compiled); use tether.envs.parallel_env or team_env"
            )
        ep.reset(ep.scenario.seed)  # the task of the scenario's seed, shared by every copy
        self.num_envs, self.n, self.dim = num_envs, ep.n, ep.dim
        self.single_observation_space = spaces.Box(
            -OBS_LIMIT, OBS_LIMIT, (ep.n, ep.obs_size), np.float32
        )
        self.single_action_space = spaces.Box(-1.0, 1.0, (ep.n, ep.dim), np.float64)
        self.observation_space = spaces.Box(
            -OBS_LIMIT, OBS_LIMIT, (num_envs, ep.n, ep.obs_size), np.float32
        )
        self.action_space = spaces.Box(-1.0, 1.0, (num_envs, ep.n, ep.dim), np.float64)
        self._world = world_arrays(ep.built.world)
        self._task = task_arrays(ep.task, num_envs, ep.n, ep.dim, s.dt_s)
        res = ep.built.world.grid.resolution_m if ep.built.world.grid is not None else 1.0
        body = ep.built.sensor.body_radius_m if ep.built.sensor.occlusion else 0.0
        self._sizes = np.array(
            [
                s.step_m,
                s.dt_s,
                s.max_speed_mps,
                s.link_range_m,
                body,
                s.collision_distance_m,
                opts.max_neighbours,
                opts.map_patch_cells,
                res,
                s.max_steps,
            ]
        )
        self._weights = np.array([ep.weights[name] for name in TERMS])
        shape = (num_envs, ep.n, ep.dim)
        self.positions, self.velocities = np.zeros(shape), np.zeros(shape)
        self._steps = np.zeros(num_envs, np.int64)
        self._obs = np.zeros((num_envs, ep.n, ep.obs_size), np.float32)
        self._terms = np.zeros((num_envs, len(TERMS)))
        self._rewards = np.zeros(num_envs)
        self._done = np.zeros(num_envs, np.int64)
        self._seeds = np.zeros(num_envs, np.int64)
        self._kernels = _kernels()
        self._plan = start_plan(ep.built)

    # -- copies ------------------------------------------------------------------------
    def _initial(self, seed: int) -> np.ndarray:
        """The team ``tether run --seed`` starts with, in the shared world."""
        ep = self.template
        built = ep.built
        scenario = ep.scenario.with_seed(seed)
        rng = np.random.default_rng(seed)
        cls = type(built.strategy)
        params = cls.Params.model_validate(scenario.strategy.params)
        state = cls.initial_state(params, scenario, built.world, rng)
        if state is None:
            state = TeamState.at_rest(place_team(scenario, built.world, built.sensor, rng))
        return state.positions

    def _start(self, copies: np.ndarray) -> None:
        """Place and reset the listed copies (positions, task state, first observation).

        The teams of all the copies are placed together (:mod:`.vector_start`); the task
        state is set for all of them at once, with the arithmetic of one copy.
        """
        copies = np.asarray(copies, np.int64)
        seeds = self._seeds[copies]
        q, placed = place(self._plan, seeds, self.n, self.dim)
        for k in np.flatnonzero(~placed):  # the strategy's own start, or no kernels
            q[k] = self._initial(int(seeds[k]))
        self.positions[copies], self.velocities[copies] = q, 0.0
        self._steps[copies] = 0
        t = self._task
        t[13][copies] = q.mean(axis=1)
        if t[0] == 1:  # the leader: the robot nearest the path's start (silent's rule)
            lead = self.template.built.strategy.leader_arg
            nearest = np.argmin(np.linalg.norm(q - t[3][0], axis=2), axis=1)
            t[1][copies] = nearest if lead is None else lead % self.n
            t[2][copies] = 0.0
        elif t[0] == 2:
            t[16][copies] = np.linalg.norm(t[15] - q[:, t[14]], axis=2)
        elif t[0] == 3:
            t[21][copies], t[22][copies], t[23][copies] = 0, 0.0, 0
        self._kernels.observe_some(
            copies,
            self.positions,
            self.velocities,
            self._steps,
            self._obs,
            self._sizes,
            self._world,
            self._task,
        )

    # -- the Gymnasium API -------------------------------------------------------------
    def reset(
        self, *, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """Every copy starts: copy ``e`` with seed ``seed + e`` (default: the scenario's)."""
        seed = check_seed(seed)
        base = self.template.scenario.seed if seed is None else seed
        self._seeds[:] = base + np.arange(self.num_envs)
        self._done[:] = 0
        self._start(np.arange(self.num_envs))
        return self._obs.copy(), {}

    def step(self, actions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict]:
        a = np.asarray(actions, dtype=float)
        if a.shape != self.action_space.shape:
            raise ValueError(f"actions must have shape {self.action_space.shape} (got {a.shape})")
        if not np.isfinite(a).all():
            raise ValueError("actions must be finite numbers")
        ended = np.flatnonzero(self._done)
        active = self._done == 0
        self._kernels.step_all(
            active,
            self.positions,
            self.velocities,
            a,
            self._steps,
            self._obs,
            self._terms,
            self._rewards,
            self._done,
            self._sizes,
            self._world,
            self._task,
            self._weights,
        )
        if len(ended):  # next-step autoreset: these copies start again instead of moving
            self._seeds[ended] += self.num_envs
            self._start(ended)
            self._done[ended] = 0
            self._rewards[ended] = 0.0
            self._terms[ended] = 0.0
        done = self._done
        return (
            self._obs.copy(),
            self._rewards.copy(),
            done == 1,
            done == 2,
            {"terms": self._terms.copy()},
        )


def _kernels() -> Any:
    """:mod:`tether.envs.vector_kernels` (imports numba; compiled on first use)."""
    from tether.envs import vector_kernels

    return vector_kernels
