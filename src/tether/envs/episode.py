"""One episode of a scenario as an environment: the core loop of ``tether run``, turned inside out.

``tether run`` calls the strategy inside :func:`tether.sim.simulate`; an environment
is called by the policy instead. :class:`Episode` keeps the loop's order and its
records exactly (reset, sense, record step 0; then per step: move, sense, record), so:

* an episode of a seed starts from what ``tether run --seed`` starts from: the same
  world, team, targets and random stream (:func:`tether.runner.build`);
* the scenario's strategy is reset with the episode and can act as a scripted policy
  (:meth:`Episode.scripted_actions`): its move is turned into the actions that land
  exactly where the strategy moved, so a scripted episode is the run of ``tether run``
  step for step, and records the same summary;
* an episode can be written as a normal run folder (:meth:`Episode.write_run`) through
  the recorder and writer of ``tether run``.
"""

from __future__ import annotations

import time
from functools import cache
from pathlib import Path
from typing import Any

import numpy as np
from threadpoolctl import ThreadpoolController

from tether.envs.observe import obs_size, observations
from tether.envs.options import EnvOptions
from tether.envs.plant import bounded, landing_actions, move
from tether.envs.rewards import reward, step_terms
from tether.envs.setting import SCRIPTED_KINDS, Setting, make_setting, make_task
from tether.record import TrajectoryRecorder
from tether.runfolder import RunFolder
from tether.runner import as_scenario, build, check_seed, write_run
from tether.sensing import Observation, sense
from tether.sim import RunResult, StepContext, StepRecord, TeamState, blas_threads, team_metrics


@cache
def _controller() -> ThreadpoolController:
    return ThreadpoolController()


def _few_blas_threads() -> Any:
    """BLAS threads as in :func:`tether.sim.simulate` (a cached controller: microseconds)."""
    return _controller().limit(limits=blas_threads(), user_api="blas")


#: a scripted step lands on the strategy's move if the actions reach it this closely
LANDING_RTOL = 1e-12


class Episode:
    """A scenario stepped by actions (see the module docstring)."""

    def __init__(self, scenario: Any, options: EnvOptions) -> None:
        self.scenario = as_scenario(scenario)
        self.options = options
        self.weights = options.weights()
        self.seed: int | None = None
        self._reset_built(self.scenario.seed)
        self.obs_size = obs_size(self.setting.dim, options.max_neighbours, options.map_patch_cells)

    # -- building --------------------------------------------------------------------
    def _reset_built(self, seed: int) -> None:
        self.built = build(self.scenario, seed)  # built.scenario carries the seed
        self.setting: Setting = make_setting(self.built, self.options)
        if self.seed is None:  # spaces are fixed by the first build
            self.n, self.dim = self.setting.n, self.setting.dim
        elif (self.setting.n, self.setting.dim) != (self.n, self.dim):
            raise ValueError(f"seed {seed} gives a team of another size or dimension")
        self.seed = seed

    def reset(self, seed: int | None = None) -> np.ndarray:
        """Start an episode of ``seed`` (default: the scenario's seed, then the next one)."""
        seed = check_seed(seed)
        if seed is None:
            seed = self.scenario.seed if self.seed is None else self.seed + 1
        self._reset_built(seed)
        built, s = self.built, self.setting
        self.rng = built.rng
        self.step_count = 0
        self.state = built.initial.copy()
        self.scripted = s.kind in SCRIPTED_KINDS
        self._pending: tuple[np.ndarray, TeamState] | None = None
        self._strategy_velocities = self.state.velocities.copy()
        self.landing_misses = 0
        self.wall_start, self.cpu_start = time.perf_counter(), time.process_time()
        with _few_blas_threads():
            if self.scripted:
                built.strategy.reset(built.world, self.state, self.rng)
            self.obs = self._sense(self.state)
        self.task = make_task(built, s, self.options)
        self.task.reset(self.state.positions)
        self.origin = self.state.positions.mean(axis=0)
        self.records: list[StepRecord] = []
        self.recorder = TrajectoryRecorder(every=built.scenario.output.record_every)
        self.episode_return = 0.0
        self.term_sums: dict[str, float] = dict.fromkeys(self.weights, 0.0)
        self.terminated = self.truncated = False
        rec = self._metrics()
        self.terms = step_terms(
            rec,
            self.obs,
            self._nodes(),
            s.n,
            s.link_range_m,
            progress=0.0,
            targets=0,
            blocked=0,
            clearance=self._clearance(),
        )
        self._record(rec, first=True)
        return self.observe()

    # -- one step ---------------------------------------------------------------------
    def step(self, actions: np.ndarray) -> tuple[np.ndarray, float, bool, bool]:
        """Move the team by ``actions`` (``(n, dim)``); returns (observations, reward,
        terminated, truncated)."""
        if self.terminated or self.truncated:
            raise RuntimeError("the episode is over; call reset() first")
        actions = self._checked(actions)
        pending, self._pending = self._pending, None
        scripted = self.scripted and pending is not None and np.array_equal(actions, pending[0])
        if not scripted:
            self.scripted = False  # the strategy's own state no longer matches the team's
        s = self.setting
        q_old = self.state.positions
        with _few_blas_threads():
            q, blocked = move(self.built.world, q_old, bounded(actions), s.step_m)
            if scripted:  # the strategy's own move, which the actions reach to rounding
                self._strategy_velocities = pending[1].velocities
                target = pending[1].positions
                if np.allclose(q, target, rtol=LANDING_RTOL, atol=LANDING_RTOL):
                    q = target.copy()
                else:
                    self.landing_misses += 1
            self.state = TeamState(q, (q - q_old) / s.dt_s, self.state.fixed)
            self.step_count += 1
            self.obs = self._sense(self.state)
            t_s = self.step_count * s.dt_s
            progress, targets = self.task.update(q_old, q, t_s)
            rec = self._metrics()
            self.terms = step_terms(
                rec,
                self.obs,
                self._nodes(),
                s.n,
                s.link_range_m,
                progress=progress,
                targets=targets,
                blocked=int(blocked.sum()),
                clearance=self._clearance(),
            )
        r = reward(self.terms, self.weights)
        self.episode_return += r
        for name, value in self.terms.items():
            self.term_sums[name] += value
        strategy_done = self.scripted and self.built.strategy.done()
        self.terminated = strategy_done if self.scripted else self.task.done()
        self.truncated = self.step_count >= s.max_steps and not self.terminated
        self._record(rec, first=False)
        return self.observe(), r, self.terminated, self.truncated

    def scripted_actions(self) -> np.ndarray:
        """The actions of the scenario's own strategy for this step (the paper's controller).

        The strategy moves the team from the current state exactly as in ``tether run``;
        the actions returned land every robot where it moved. Pass them to :meth:`step`
        unchanged to keep the episode scripted (any other actions end that for the rest
        of the episode).
        """
        if not self.scripted:
            why = (
                "this scenario's strategy has no scripted policy"
                if self.setting.kind not in SCRIPTED_KINDS
                else "other actions were taken in this episode"
            )
            raise RuntimeError(f"no scripted actions: {why}; reset() starts a new episode")
        if self.terminated or self.truncated:
            raise RuntimeError("the episode is over; call reset() first")
        s = self.setting
        state = TeamState(self.state.positions, self._strategy_velocities, self.state.fixed)
        ctx = StepContext(
            self.step_count,
            self.step_count * s.dt_s,
            s.dt_s,
            self.built.world,
            state,
            self.obs,
            self.rng,
        )
        with _few_blas_threads():
            moved = self.built.strategy.step(ctx)
        actions, _ = landing_actions(self.state.positions, moved.positions, s.step_m)
        self._pending = (actions.copy(), moved)
        return actions

    # -- what the loop computes -------------------------------------------------------
    def _checked(self, actions: Any) -> np.ndarray:
        a = np.asarray(actions, dtype=float)
        if a.shape != (self.n, self.dim):
            raise ValueError(f"actions must have shape ({self.n}, {self.dim}) (got {a.shape})")
        if not np.isfinite(a).all():
            raise ValueError("actions must be finite numbers")
        return a

    def _sense(self, state: TeamState) -> Observation:
        s, built = self.setting, self.built
        if s.kind == "exploration":
            nodes = state.positions if s.fixed is None else np.vstack([state.positions, s.fixed])
            return sense(nodes, s.link_sensor, self.rng, built.world)
        return built.strategy.sense(state, built.world, built.sensor, self.rng)

    def _nodes(self) -> np.ndarray:
        q, fixed = self.state.positions, self.setting.fixed
        return q if fixed is None or self.setting.kind != "exploration" else np.vstack([q, fixed])

    def _metrics(self) -> StepRecord:
        s = self.setting
        rec = team_metrics(
            self.step_count,
            self.step_count * s.dt_s,
            self.state.positions,
            self.obs,
            s.collision_distance_m,
        )
        self.records.append(rec)
        return rec

    def _clearance(self) -> int:
        world = self.built.world
        if not world.has_obstacles or self.setting.clearance_m <= 0:
            return 0
        return int((world.clearance_m(self.state.positions) < self.setting.clearance_m).sum())

    def observe(self) -> np.ndarray:
        """``(n, obs_size)`` float32 observations of the current state."""
        s = self.setting
        return observations(
            self.obs,
            self.state.positions,
            self.state.velocities,
            self.origin,
            self.task.offsets(self.state.positions, self.step_count * s.dt_s),
            max_speed_mps=s.max_speed_mps,
            range_m=s.link_range_m,
            max_neighbours=self.options.max_neighbours,
            world=self.built.world,
            patch_cells=self.options.map_patch_cells,
        )

    # -- records ----------------------------------------------------------------------
    def _record(self, rec: StepRecord, first: bool) -> None:
        if not self.options.record:
            return
        strategy = self.built.strategy
        own = self.scripted
        values = dict(strategy.step_values()) if own else {}
        robot_values = dict(strategy.robot_values()) if own else {}
        events = strategy.drain_events() if own else []
        values.update(
            reward=0.0 if first else reward(self.terms, self.weights),
            task_progress=self.terms["progress"],
        )
        self.recorder.record(
            rec, self.state, self.obs, events, values, robot_values if self.scripted else {}
        )

    def metrics(self) -> dict[str, Any]:
        """The episode's own summary keys: its return, every term's sum, the task's."""
        out: dict[str, Any] = {
            "policy": "scripted" if self.scripted else "actions",
            "episode_return": self.episode_return,
            **{f"term_{k}": v for k, v in self.term_sums.items()},
            **self.task.metrics(),
        }
        if self.scripted:
            out["landing_misses"] = self.landing_misses
        return out

    def write_run(self, out_dir: str | Path, *, figures: bool | None = None) -> dict[str, Any]:
        """Write the episode so far as a run folder (``record=True``); returns its summary.

        A scripted episode's folder is the folder of ``tether run`` (same tables and
        summary, plus the episode's own keys); any other episode's summary holds the
        episode's keys instead of the strategy's metrics.
        """
        if not self.options.record:
            raise RuntimeError("create the environment with record=True to write run folders")
        built = self.built
        strategy_metrics = built.strategy.metrics() if self.scripted else {}
        result = RunResult(
            steps=self.step_count,
            sim_time_s=self.step_count * self.setting.dt_s,
            wall_time_s=time.perf_counter() - self.wall_start,
            records=list(self.records),
            final_state=self.state.copy(),
            strategy_metrics=strategy_metrics,
            cpu_time_s=time.process_time() - self.cpu_start,
        )
        folder = RunFolder(Path(out_dir))
        return write_run(
            folder,
            built,
            self.recorder,
            result,
            self.seed,
            result.wall_time_s,
            figures=figures,
            extra={"environment": self.metrics()},
        )
