"""The ``silent`` strategy: leader-follower navigation without communication.

Followers run the Local Steering Strategy (:mod:`tether.silent.steering`);
the leader (``R_N``, hidden: nobody treats it differently) follows a given
trajectory, subject to the same constraints (1) and (2) so that it cannot
break the group. Source: Kerestecioglu & Cezayirli, sections III-B and IV.
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, Field, field_validator, model_validator

from tether import floats
from tether.config import MAX_LENGTH_M, Coordinate, Scenario, finite_strict
from tether.errors import ScenarioError
from tether.paths.trajectory import Polyline, TimeFunction
from tether.registry import STRATEGIES
from tether.silent import steering
from tether.silent.steering import team_steps
from tether.sim import StepContext, Strategy, TeamState
from tether.usercode import CODE_FIELD, UserCodeError, resolve_callable
from tether.viz.plots import team_snapshot
from tether.world.world import World


class TrajectoryParams(BaseModel):
    """Leader trajectory: ``waypoints`` at ``speed_mps``, or a Python function of time."""

    model_config = finite_strict()
    kind: Literal["waypoints", "function"] = Field(
        default="waypoints", description="a polyline of waypoints, or a Python function"
    )
    waypoints: list[list[Coordinate]] | None = Field(
        default=None, description="waypoints: at least two points (m)"
    )
    speed_mps: float = Field(
        default=1.0, gt=0, le=MAX_LENGTH_M, description="waypoints: the leader's speed"
    )
    function: str | None = Field(
        default=None,
        description="'module:callable' mapping t_s -> position, in a module the user has "
        "loaded (never imported from the scenario: tether.usercode)",
        json_schema_extra=CODE_FIELD,
    )
    goal_tolerance_m: float = Field(
        default=0.5, gt=0, le=MAX_LENGTH_M, description="the leader is at its goal within this"
    )

    @model_validator(mode="after")
    def _complete(self) -> TrajectoryParams:
        if self.kind == "waypoints" and (not self.waypoints or len(self.waypoints) < 2):
            raise ValueError("kind 'waypoints' needs a 'waypoints' list of at least 2 points")
        if self.kind == "function" and not self.function:
            raise ValueError("kind 'function' needs 'function: module:callable'")
        if self.kind == "waypoints" and self.function is not None:
            raise ValueError("'function' is used only with kind 'function'; remove it")
        return self

    @field_validator("waypoints")
    @classmethod
    def _same_dimension(cls, value: list[list[float]] | None) -> list[list[float]] | None:
        sizes = [len(p) for p in value or []]
        if len(set(sizes)) > 1:
            k = next(i for i, n in enumerate(sizes) if n != sizes[0])
            raise ValueError(
                f"waypoint {k} has {sizes[k]} coordinates and waypoint 0 has {sizes[0]}; give "
                "every waypoint the world's dimension"
            )
        return value


class SilentParams(BaseModel):
    """Parameters of the non-communicating strategy (paper section V defaults)."""

    model_config = finite_strict()
    cost: Literal["desired_distance", "farthest"] = Field(
        default="desired_distance", description="cost (13) with d0, or cost (12)"
    )
    d0_m: float = Field(
        default=11.0, gt=0, le=MAX_LENGTH_M, description="desired distance d0 of cost (13)"
    )
    gamma: float = Field(default=0.2, gt=0, description="gain of the gradient step (14)")
    leader: int | None = Field(
        default=None,
        description="index of the leader R_N (default: the robot nearest the trajectory's start)",
    )
    trajectory: TrajectoryParams = Field(description="the leader's path")
    max_speed_mps: float | None = Field(
        default=None, gt=0, le=MAX_LENGTH_M, description="speed bound (null: none)"
    )
    min_separation_m: float = Field(
        default=0.0, ge=0, le=MAX_LENGTH_M, description="steps keep robots this far apart"
    )
    search_directions: bool = Field(
        default=True,
        description="if the desired direction is blocked, also try heading at each sensed "
        "robot (see steering.constrained_steps); false: the paper's shrink-only step",
    )
    robust: bool = Field(
        default=True,
        description="evaluate (1)-(2) for the worst true position within the sensor's error "
        "bounds (false: trust measurements as the paper's noise-free theorem does)",
    )


def _number(name: str, value: Any, *, lo: float = 0.0, strict: bool = True) -> None:
    """``value`` must be a real finite number above ``lo`` (or at least ``lo``)."""
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise TypeError(f"{name} must be a number (got {type(value).__name__} {value!r})")
    if not np.isfinite(value) or (value <= lo if strict else value < lo):
        bound = f"> {lo:g}" if strict else f">= {lo:g}"
        raise ValueError(f"{name} must be a finite number {bound} (got {value!r})")


def _check_args(**kw: Any) -> None:
    """The arguments of :class:`SilentStrategy`, checked up front with a clear message."""
    for name in ("d_max_m", "d0_m", "gamma", "speed_mps", "goal_tolerance_m"):
        _number(name, kw[name])
    for name in ("radial_error_m", "angular_error_rad", "min_separation_m"):
        _number(name, kw[name], strict=False)
    if kw["max_speed_mps"] is not None:
        _number("max_speed_mps", kw["max_speed_mps"])
    if kw["radial_error_m"] >= kw["d_max_m"]:
        raise ValueError("radial_error_m must be smaller than d_max_m")
    if kw["angular_error_rad"] >= np.pi / 2:
        raise ValueError(f"angular_error_rad must be below pi/2 (got {kw['angular_error_rad']!r})")
    if kw["cost"] not in ("desired_distance", "farthest"):
        raise ValueError(f"cost must be 'desired_distance' or 'farthest' (got {kw['cost']!r})")
    leader = kw["leader"]
    if leader is not None and (
        isinstance(leader, bool) or not isinstance(leader, int | np.integer)
    ):
        raise TypeError(f"leader must be a robot index or None (got {leader!r})")
    if not isinstance(kw["trajectory"], Polyline) and not callable(kw["trajectory"]):
        raise TypeError(
            "trajectory must be a Polyline or a function of time "
            f"(got {type(kw['trajectory']).__name__})"
        )


@STRATEGIES.register("silent")
class SilentStrategy(Strategy):
    """Leader-follower Local Steering Strategy (no communication, unlabelled robots)."""

    name = "silent"
    Params = SilentParams
    #: said at the end of a run among obstacles that lost connectivity (``tether run``)
    free_space_guarantee = (
        "silent's guarantee (Theorem 1 of its paper) holds in free space: among obstacles, "
        "a wall that comes between two robots in range cuts their link without warning"
    )

    def __init__(
        self,
        *,
        d_max_m: float,
        trajectory: Polyline | TimeFunction,
        leader: int | None = None,
        cost: str = "desired_distance",
        d0_m: float = 11.0,
        gamma: float = 0.2,
        radial_error_m: float = 0.0,
        angular_error_rad: float = 0.0,
        speed_mps: float = 1.0,
        max_speed_mps: float | None = None,
        min_separation_m: float = 0.0,
        goal_tolerance_m: float = 0.5,
        search_directions: bool = True,
    ) -> None:
        super().__init__()
        _check_args(
            d_max_m=d_max_m,
            trajectory=trajectory,
            leader=leader,
            cost=cost,
            d0_m=d0_m,
            gamma=gamma,
            radial_error_m=radial_error_m,
            angular_error_rad=angular_error_rad,
            speed_mps=speed_mps,
            max_speed_mps=max_speed_mps,
            min_separation_m=min_separation_m,
            goal_tolerance_m=goal_tolerance_m,
        )
        self.d_max_m = d_max_m
        self.trajectory = trajectory
        self.leader_arg = leader
        self.cost = cost
        self.d0_m = d0_m
        self.gamma = gamma
        self.radial_error_m = radial_error_m
        self.angular_error_rad = angular_error_rad
        self.speed_mps = speed_mps
        self.max_speed_mps = max_speed_mps
        self.min_separation_m = min_separation_m
        self.goal_tolerance_m = goal_tolerance_m
        self.search_directions = search_directions

    # -- construction from a scenario -------------------------------------------------
    @classmethod
    def from_scenario(
        cls,
        params: SilentParams,
        scenario: Scenario,
        world: World,
        initial: TeamState,
        rng: np.random.Generator,
    ) -> SilentStrategy:
        src = scenario.source
        field = "strategy.params.trajectory"
        traj = params.trajectory
        if traj.kind == "waypoints":
            pts = np.asarray(traj.waypoints, dtype=float)
            if pts.shape[1] != world.dim:
                raise ScenarioError(
                    f"{src}: {field}.waypoints: expected points of {world.dim} coordinates "
                    f"(got {pts.shape[1]})"
                )
            path: Polyline | TimeFunction = Polyline(pts)
            check_path_clear(path, world, src, field)
        else:
            try:
                path = resolve_callable(traj.function)
            except UserCodeError as exc:
                raise ScenarioError(f"{src}: {field}.function: {exc}") from None
            _check_time_function(path, world.dim, src, f"{field}.function")
        n = initial.n
        if params.leader is not None and not -n <= params.leader < n:
            raise ScenarioError(
                f"{src}: strategy.params.leader: must be a robot index in [-{n}, {n - 1}] "
                f"(got {params.leader})"
            )
        sensing = scenario.sensing
        robust = params.robust
        return cls(
            d_max_m=sensing.range_m,
            trajectory=path,
            leader=params.leader,
            cost=params.cost,
            d0_m=params.d0_m,
            gamma=params.gamma,
            radial_error_m=sensing.radial_error_m,
            angular_error_rad=sensing.angular_error_rad if robust else 0.0,
            speed_mps=traj.speed_mps,
            max_speed_mps=params.max_speed_mps,
            min_separation_m=params.min_separation_m,
            goal_tolerance_m=traj.goal_tolerance_m,
            search_directions=params.search_directions,
        )

    # -- the Strategy protocol ---------------------------------------------------------
    def reset(self, world: World, state: TeamState, rng: np.random.Generator) -> None:
        super().reset(world, state, rng)
        self.world = world
        if self.leader_arg is None:
            start = (
                self.trajectory.waypoints[0]
                if isinstance(self.trajectory, Polyline)
                else np.asarray(self.trajectory(0.0), dtype=float)
            )
            self.leader = int(np.argmin(np.linalg.norm(state.positions - start, axis=1)))
        else:
            self.leader = self.leader_arg % state.n
        self.progress_m = 0.0
        self._done = False
        self._leader_travel_m = 0.0
        self._blocked_steps = 0
        self._stuck = 0
        # the whole step in one compiled call (steering_kernels.silent_step_kernel): a
        # waypoint path, cost (13), free space; the path's per-segment values for it
        traj = self.trajectory
        self._path = None
        if (
            isinstance(traj, Polyline)
            and self.cost == "desired_distance"
            and not world.has_obstacles
            and world.bounds_m is None
        ):
            self._path = (
                traj.waypoints, traj._seg, np.array(traj._denom, dtype=float), traj._cum,
                traj._seg_len, traj.length_m, traj.end, float(2 * self.d_max_m),
                float(self.gamma), float(self.d0_m), float(self.d_max_m),
                float(self.radial_error_m), float(self.angular_error_rad),
                float(self.min_separation_m), bool(self.search_directions),
            )  # fmt: skip

    def leader_target(self, position: np.ndarray, t_next_s: float, dt_s: float) -> np.ndarray:
        """Where the leader wants to be at ``t + dt`` (a carrot ahead on the path)."""
        if isinstance(self.trajectory, Polyline):
            s = self.trajectory.project(position, self.progress_m, window_m=2 * self.d_max_m)
            self.progress_m = max(self.progress_m, s)
            return self.trajectory.at(self.progress_m + self.speed_mps * dt_s)
        return np.asarray(self.trajectory(t_next_s), dtype=float)

    def step(self, ctx: StepContext) -> TeamState:
        self._step = ctx.step
        obs, state = ctx.obs, ctx.state
        if (
            self._path is not None
            and steering._use_kernel(state.n)
            and obs.measured.ndim == 2
            and state.positions.ndim == 2
        ):
            return self._step_compiled(ctx)
        leader = self.leader
        target = self.leader_target(state.positions[leader], ctx.t_s + ctx.dt_s, ctx.dt_s)
        leader_step = target - state.positions[leader]
        max_step = np.inf if self.max_speed_mps is None else self.max_speed_mps * ctx.dt_s
        steps = team_steps(
            obs.measured,
            obs.indptr,
            leader,
            leader_step,
            cost=self.cost,
            gamma=self.gamma,
            d0_m=self.d0_m,
            d_max_m=self.d_max_m,
            radial_error_m=self.radial_error_m,
            angular_error_rad=self.angular_error_rad,
            min_separation_m=self.min_separation_m,
            max_step_m=max_step,
            search_directions=self.search_directions,
        )
        steps = self._avoid_obstacles(state.positions, steps)
        wanted = floats.norm(leader_step)
        moved = floats.norm(steps[leader])
        if wanted > 1e-9 and moved < 0.05 * wanted:
            self._blocked_steps += 1
        self._leader_travel_m += moved
        new_positions = state.positions + steps
        velocities = steps / ctx.dt_s
        self._update_done(new_positions[leader], ctx)
        return TeamState(new_positions, velocities)

    def _step_compiled(self, ctx: StepContext) -> TeamState:
        """:meth:`step` in one call of :func:`tether.silent.steering_kernels.silent_step_kernel`
        (the same arithmetic: the same positions, progress and leader statistics)."""
        obs, state = ctx.obs, ctx.state
        max_step = np.inf if self.max_speed_mps is None else self.max_speed_mps * ctx.dt_s
        positions, velocities, (progress, wanted, moved, gap) = (
            steering._kernels().silent_step_kernel(
                np.ascontiguousarray(state.positions, dtype=float),
                np.ascontiguousarray(obs.measured, dtype=float),
                obs.indptr.astype(np.int64, copy=False), self.leader, *self._path,
                float(self.progress_m), float(self.speed_mps * ctx.dt_s), float(ctx.dt_s),
                float(max_step),
            )
        )  # fmt: skip
        self.progress_m = progress
        if wanted > 1e-9 and moved < 0.05 * wanted:
            self._blocked_steps += 1
        self._leader_travel_m += moved
        self._done = bool(gap <= self.goal_tolerance_m)
        return TeamState(positions, velocities)

    def _avoid_obstacles(self, positions: np.ndarray, steps: np.ndarray) -> np.ndarray:
        """Halve steps (direction kept) until their segments stay in free space."""
        if not self.world.has_obstacles and self.world.bounds_m is None:
            return steps
        steps = steps.copy()
        active = np.linalg.norm(steps, axis=1) > 0
        for _ in range(12):
            idx = np.nonzero(active)[0]
            if len(idx) == 0:
                break
            ok = self.world.segments_clear(positions[idx], positions[idx] + steps[idx])
            ok &= self.world.points_free(positions[idx] + steps[idx])
            active[idx[ok]] = False
            steps[idx[~ok]] *= 0.5
        steps[active] = 0.0
        return steps

    def _update_done(self, leader_pos: np.ndarray, ctx: StepContext) -> None:
        if isinstance(self.trajectory, Polyline):
            at_end = floats.norm(leader_pos - self.trajectory.end) <= self.goal_tolerance_m
            self._done = bool(at_end)

    def done(self) -> bool:
        return self._done

    def figures(self, recording: Any, world: World, dt_s: float) -> dict[str, Any]:
        """The paper's Fig. 4: the team at three instants, with the leader and its path."""
        path = self.trajectory.waypoints if isinstance(self.trajectory, Polyline) else None
        fig = team_snapshot(
            recording,
            world,
            dt_s,
            range_m=self.d_max_m,
            leader=self.leader,
            path=path,
            path_label="leader's path",
            title="silent: the team following its leader",
        )
        return {} if fig is None else {"snapshot.png": fig}

    def metrics(self) -> dict[str, Any]:
        out: dict[str, Any] = {
            "leader_reached_goal": self._done,
            "leader_travel_m": self._leader_travel_m,
            "leader_blocked_steps": self._blocked_steps,
        }
        if isinstance(self.trajectory, Polyline):
            out["path_length_m"] = self.trajectory.length_m
            out["path_progress"] = self.progress_m / max(self.trajectory.length_m, 1e-12)
        return out


def _check_time_function(fn: TimeFunction, dim: int, source: str, field: str) -> None:
    """The leader's function of time must give a finite point of ``dim`` coordinates."""
    try:
        point = np.asarray(fn(0.0), dtype=float)
    except Exception as exc:  # the user's function: any failure is a problem of the input
        raise ScenarioError(
            f"{source}: {field}: calling it at t = 0 s raised {type(exc).__name__}: {exc}"
        ) from None
    if point.shape != (dim,) or not np.isfinite(point).all():
        raise ScenarioError(
            f"{source}: {field}: must return {dim} finite coordinates for a time in seconds "
            f"(at t = 0 s it gave {point.tolist()})"
        )


def check_path_clear(path: Polyline, world: World, source: str, field: str) -> None:
    """Raise a one-line ScenarioError if a waypoint path leaves free space."""
    pts = path.waypoints
    free = world.points_free(pts)
    if not free.all():
        k = int(np.argmin(free))
        raise ScenarioError(
            f"{source}: {field}.waypoints[{k}]: point {pts[k].tolist()} is inside an obstacle "
            "or outside the world; move it into free space"
        )
    a, b = path.segments()
    clear = world.segments_clear(a, b)
    if not clear.all():
        k = int(np.argmin(clear))
        raise ScenarioError(
            f"{source}: {field}.waypoints: segment {k}->{k + 1} passes through an obstacle; "
            "add a waypoint around it"
        )
