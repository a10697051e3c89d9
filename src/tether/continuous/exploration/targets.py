"""Targets of the multi-target exploration and their generators (Sec. 2.1, Sec. 4.1).

Every robot has a queue of targets ``z_i^k`` with stay times ``Delta t_i^k``; the
robot must stay within ``Rz`` of a target for ``Delta t`` to complete it. The
queues are filled by *target generators*, registered by name in
:data:`tether.registry.TARGET_GENERATORS` and chosen in YAML
(``strategy.params.targets: {kind: ..., params: {...}}``):

* ``fixed``: given per-robot lists;
* ``paper_random``: the paper's Monte Carlo trials: 5 robots get 3 targets, 5
  robots get 2, the rest none, drawn from a *configuration seed* independent of
  the team size, so one configuration is reused for every ``N`` (Sec. 4.1);
* ``schedule``: targets that appear at given times.

Targets can also be added while the team runs, from Python
(:meth:`TargetBook.add`, e.g. ``strategy.targets.add(robot, position)``).
A target may carry a ``timeout_s``: a robot that has not completed it that long
after taking it up drops it and moves on (the paper's closing suggestion for
targets that expire); unreachable targets are dropped the same way.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import Annotated, Any, ClassVar

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, field_validator

from tether.registry import TARGET_GENERATORS
from tether.world.scenes import free_positions
from tether.world.world import World


@dataclass
class Target:
    """One location to visit: where, how long to stay, when it appears, when it expires."""

    position_m: np.ndarray
    stay_s: float = 3.0
    appear_s: float = 0.0
    timeout_s: float | None = None
    id: int = -1


@dataclass
class TargetBook:
    """The target queues of all robots (each robot reads only its own)."""

    queues: list[deque[Target]]
    total: int = 0
    _next_id: int = field(default=0, repr=False)

    @classmethod
    def empty(cls, n: int) -> TargetBook:
        return cls([deque() for _ in range(n)])

    def add(
        self,
        robot: int,
        position_m: Any,
        stay_s: float = 3.0,
        *,
        appear_s: float = 0.0,
        timeout_s: float | None = None,
    ) -> Target:
        """Append a target to ``robot``'s queue (also while the team runs)."""
        if not 0 <= robot < len(self.queues):
            raise ValueError(f"robot must be in [0, {len(self.queues) - 1}] (got {robot})")
        pos = np.asarray(position_m, dtype=float).ravel()
        if not np.all(np.isfinite(pos)):
            raise ValueError(f"target position must be finite (got {position_m!r})")
        if not (np.isfinite(stay_s) and stay_s >= 0):
            raise ValueError(f"stay_s must be finite and >= 0 (got {stay_s!r})")
        target = Target(pos, float(stay_s), float(appear_s), timeout_s, self._next_id)
        self._next_id += 1
        self.total += 1
        self.queues[robot].append(target)
        return target

    def take(self, robot: int, t_s: float) -> Target | None:
        """Pop ``robot``'s next target if it has appeared by ``t_s``."""
        queue = self.queues[robot]
        if queue and queue[0].appear_s <= t_s + 1e-12:
            return queue.popleft()
        return None

    def has_targets(self, robot: int) -> bool:
        return bool(self.queues[robot])

    def pending(self) -> int:
        """Targets still queued (appeared or not)."""
        return sum(len(q) for q in self.queues)


#: at most this many targets from one ``paper_random`` generator (the paper draws 25)
MAX_TARGETS = 100_000


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False)


def height_range(v: list[float] | None) -> list[float] | None:
    """``v`` if it is ``None`` or ``[low, high]`` with ``low <= high``; else a clear error."""
    if v is None:
        return v
    if len(v) != 2:
        raise ValueError(f"need two heights [low, high] in m (got {v})")
    if not v[0] <= v[1]:
        raise ValueError(f"need low <= high in [low, high] (got {v}); swap them")
    return v


class TargetGenerator:
    """A registered generator: a ``Params`` model and :meth:`fill`."""

    Params: ClassVar[type[BaseModel]]

    @classmethod
    def fill(
        cls, params: Any, book: TargetBook, world: World, rng: np.random.Generator
    ) -> None:  # pragma: no cover - interface
        raise NotImplementedError


class FixedQueue(_Strict):
    robot: int = Field(ge=0)
    targets: list[list[float]]
    stay_s: float = Field(default=3.0, ge=0, allow_inf_nan=False)
    timeout_s: float | None = Field(default=None, gt=0, description="overrides the default")

    @field_validator("targets")
    @classmethod
    def _finite(cls, v: list[list[float]]) -> list[list[float]]:
        if not v or not all(np.all(np.isfinite(p)) for p in v):
            raise ValueError("need a non-empty list of finite points")
        return v


class FixedParams(_Strict):
    queues: list[FixedQueue]
    timeout_s: float | None = Field(default=None, gt=0)


@TARGET_GENERATORS.register("fixed")
class Fixed(TargetGenerator):
    """Given per-robot target lists with their stay times."""

    Params = FixedParams

    @classmethod
    def fill(cls, params: FixedParams, book: TargetBook, world: World, rng: Any) -> None:
        for q in params.queues:  # queues of one robot are visited in the order given
            for p in q.targets:
                book.add(q.robot, p, q.stay_s, timeout_s=q.timeout_s or params.timeout_s)


class ScheduledTarget(_Strict):
    robot: int = Field(ge=0)
    position_m: list[float]
    at_s: float = Field(default=0.0, ge=0, allow_inf_nan=False)
    stay_s: float = Field(default=3.0, ge=0, allow_inf_nan=False)


class ScheduleParams(_Strict):
    targets: list[ScheduledTarget]
    timeout_s: float | None = Field(default=None, gt=0)


@TARGET_GENERATORS.register("schedule")
class Schedule(TargetGenerator):
    """Targets that appear at given times (``at_s``), in the order given per robot."""

    Params = ScheduleParams

    @classmethod
    def fill(cls, params: ScheduleParams, book: TargetBook, world: World, rng: Any) -> None:
        for t in sorted(params.targets, key=lambda t: t.at_s):
            book.add(t.robot, t.position_m, t.stay_s, appear_s=t.at_s, timeout_s=params.timeout_s)


class PaperRandomParams(_Strict):
    """The paper's random trials (Sec. 4.1): which robots get how many targets, where."""

    config_seed: int = Field(default=0, ge=0, description="same targets for every team size")
    explorers: list[Annotated[int, Field(ge=0)]] = Field(
        default=[3, 3, 3, 3, 3, 2, 2, 2, 2, 2],
        description="targets per explorer: robots 0, 1, ... in this order",
    )
    stay_s: float = Field(default=3.0, ge=0, allow_inf_nan=False)
    clearance_m: float = Field(default=2.0, ge=0, allow_inf_nan=False)
    height_m: list[float] | None = Field(default=None, description="[min, max] z in 3-D")
    timeout_s: float | None = Field(default=None, gt=0)

    _heights = field_validator("height_m")(height_range)

    @field_validator("explorers")
    @classmethod
    def _at_most(cls, v: list[int]) -> list[int]:
        if sum(v) > MAX_TARGETS:
            raise ValueError(
                f"{sum(v):,} targets in all, more than the {MAX_TARGETS:,} allowed; "
                "give fewer targets per explorer"
            )
        return v


@TARGET_GENERATORS.register("paper_random")
class PaperRandom(TargetGenerator):
    """Uniform targets in the free space (largest connected region, with clearance).

    Drawn from ``numpy.random.default_rng(config_seed)`` alone: the run seed and
    the team size do not change them, so configuration ``k`` is the same for
    every ``N`` (robots ``0..len(explorers)-1`` are the explorers).
    """

    Params = PaperRandomParams

    @classmethod
    def fill(cls, params: PaperRandomParams, book: TargetBook, world: World, rng: Any) -> None:
        if len(params.explorers) > len(book.queues):
            raise ValueError(
                f"{len(params.explorers)} explorers but only {len(book.queues)} robots; "
                "raise team.n_robots or shorten targets.params.explorers"
            )
        why = outside_heights(params.height_m, world)
        if why is not None:
            raise ValueError(f"height_m: {why}")
        config = np.random.default_rng(params.config_seed)
        count = int(sum(params.explorers))
        pts = draw_free_points(world, count, config, params.clearance_m, params.height_m)
        k = 0
        for robot, m in enumerate(params.explorers):
            for _ in range(m):
                book.add(robot, pts[k], params.stay_s, timeout_s=params.timeout_s)
                k += 1


def draw_free_points(
    world: World,
    count: int,
    rng: np.random.Generator,
    clearance_m: float,
    height_m: list[float] | None = None,
) -> np.ndarray:
    """``count`` uniform points of the largest free region with ``clearance_m`` to obstacles.

    In 3-D, ``height_m = [lo, hi]`` restricts the height (rejection sampling on
    the cells of that slab, so the points stay uniform over it).
    """
    if height_m is None or world.dim == 2:
        return free_positions(world, count, rng, clearance_m, same_component=True)
    lo, hi = float(height_m[0]), float(height_m[1])
    out: list[np.ndarray] = []
    for _ in range(1000):
        pts = free_positions(world, max(4 * count, 16), rng, clearance_m, same_component=True)
        out.extend(pts[(pts[:, 2] >= lo) & (pts[:, 2] <= hi)])
        if len(out) >= count:
            return np.asarray(out[:count])
    raise ValueError(f"no free point with clearance {clearance_m} m at heights [{lo}, {hi}] m")


def outside_heights(height_m: list[float] | None, world: World) -> str | None:
    """Why a ``[low, high]`` height range misses the 3-D world's heights (``None``: it does not)."""
    if height_m is None or world.dim != 3 or world.bounds_m is None:
        return None
    lo, hi = (float(b[2]) for b in world.bounds_m)
    if height_m[1] < lo or height_m[0] > hi:
        return (
            f"{list(height_m)} m is outside the world's heights [{lo:g}, {hi:g}] m; "
            "give a range within them"
        )
    return None
