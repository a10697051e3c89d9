"""Where the copies of the vector form start: one compiled call places every copy's team.

Copy ``e`` of ``reset(seed=s)`` starts where ``tether run --seed s+e`` starts, bit for
bit. Which way the teams are placed depends on the scenario (:func:`start_plan`):

* a strategy that places its own team (``initial_state``, e.g. ``multi_target``'s safe
  start): in Python, copy by copy, through the strategy;
* ``team.init`` ``grid`` or ``positions``: the same team for every seed, placed once;
* ``random_connected`` or ``uniform``: :func:`tether.envs.vector_placement.place_all`,
  every copy in one call (numba). The random numbers are not drawn by numpy but by
  :mod:`tether.envs.vector_random`, which computes ``np.random.default_rng(seed)``'s
  stream from the seed inside the kernel. Drawing them with numpy instead (one
  generator per copy, or a block of numbers per copy drawn ahead) costs a generator per
  copy (about the time of placing a 3-robot team) and, since how many numbers a copy
  draws depends on which candidates are refused, either a guess of how many to draw or
  a return to Python; the compiled stream has neither, and ``tests/test_envs_placement.py``
  checks it against numpy draw by draw;
* with the kernels switched off (``TETHER_JIT=0``, :func:`tether.jit.set_enabled`), the
  Python placement of ``tether run`` (:func:`tether.runner.place_team`) for every copy.

A copy the kernel cannot place (no room left, a team not connected in the sensing graph)
is placed in Python, which raises ``tether run``'s error for that seed.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from tether import jit
from tether.config import InitConfig
from tether.sim import Strategy
from tether.team import default_center, random_connected, uniform_connected, uniform_tries
from tether.world.world import World

#: ``team.init`` kinds that give every seed the same team
FIXED_KINDS = ("grid", "positions")
#: place_all's codes of the compiled kinds (tether.envs.vector_placement)
COMPILED_KINDS = {"random_connected": 1, "uniform": 2}


def _default(fn: Callable[..., Any], name: str) -> Any:
    return inspect.signature(fn).parameters[name].default


@dataclass(frozen=True)
class StartPlan:
    """How the copies' teams are placed: ``fixed`` (every seed's team), ``args``
    (:func:`~tether.envs.vector_placement.place_all`'s arguments after the seeds and
    outputs), or neither (the strategy places the team, in Python)."""

    fixed: np.ndarray | None = None
    args: tuple | None = None


def world_tuple(world: World, *, keep_grid: bool) -> tuple:
    """The world tuple of :mod:`tether.envs.vector_world`.

    ``keep_grid``: keep the grid even without obstacles, so that the placement kernels
    answer ``World.points_free`` and ``World.segments_clear`` exactly; the step kernels
    (``keep_grid=False``) skip an obstacle-free grid.
    """
    grid = world.grid
    has_bounds = world.bounds_m is not None
    bounds = world.bounds_m if has_bounds else np.zeros((2, world.dim))
    if grid is None or not (keep_grid or world.has_obstacles):
        one = np.ones(world.dim, np.int64)
        return (False, np.ones(1, np.bool_), one, np.zeros(world.dim), 1.0, np.zeros(0),
                has_bounds, bounds, 1.0)  # fmt: skip
    field = grid.__dict__.get("distance_field_m")
    field = np.zeros(0) if field is None or not field.flags.c_contiguous else field.ravel()
    return (
        True,
        np.ascontiguousarray(grid.free_mask()).ravel(),
        np.asarray(grid.shape, np.int64),
        np.asarray(grid.origin_m, float),
        1.0 / grid.resolution_m,
        field,
        has_bounds,
        bounds,
        float(grid.resolution_m),
    )


def start_plan(built: Any) -> StartPlan:
    """The :class:`StartPlan` of a built scenario (:func:`tether.runner.build`)."""
    cls = type(built.strategy)
    if getattr(cls.initial_state, "__func__", None) is not Strategy.initial_state.__func__:
        return StartPlan()
    init = built.scenario.team.init
    if init.kind in FIXED_KINDS:
        return StartPlan(fixed=built.initial.positions.copy())
    return compiled_plan(init, built.scenario.team.n_robots, built.world, built.sensor.range_m)


def compiled_plan(init: InitConfig, n: int, world: World, range_m: float) -> StartPlan:
    """The plan of ``team.init`` ``random_connected`` or ``uniform`` (of ``n`` robots in
    ``world``, linked within ``range_m``)."""
    dim = world.dim
    center = default_center(world) if init.center is None else np.asarray(init.center, float)
    if init.kind == "uniform":
        extent = np.broadcast_to(np.asarray(init.extent_m, float), (dim,)).copy()
        tries = uniform_tries(n, _default(uniform_connected, "max_tries"))
        size = 0.0
    else:
        extent = np.zeros(dim)
        tries = int(_default(random_connected, "max_tries"))
        size = float(init.spacing_m)
    args = (COMPILED_KINDS[init.kind], center.astype(float), size, extent, float(range_m),
            float(init.min_separation_m), int(tries), world_tuple(world, keep_grid=True),
            bool(world.has_obstacles))  # fmt: skip
    return StartPlan(args=args)


def place(plan: StartPlan, seeds: np.ndarray, n: int, dim: int) -> tuple[np.ndarray, np.ndarray]:
    """The teams of ``seeds``, ``(len(seeds), n, dim)``, and which of them are placed.

    Copies not placed (``False``) are left to the caller's Python placement: all of
    them when the plan has no compiled kind or the kernels are switched off.
    """
    out = np.zeros((len(seeds), n, dim))
    ok = np.zeros(len(seeds), np.bool_)
    if plan.fixed is not None:
        out[:] = plan.fixed
        ok[:] = True
    elif plan.args is not None and jit.allowed() and len(seeds):
        from tether.envs import vector_placement

        vector_placement.place_all(np.asarray(seeds, np.int64), out, ok, *plan.args)
    return out, ok
