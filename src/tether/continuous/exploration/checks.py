"""Up-front checks of a ``multi_target`` scenario that need its world, and its targets.

Run from :meth:`MultiTargetStrategy.from_scenario`, i.e. in
:func:`tether.runner.build`, which ``tether validate`` and ``tether run`` both
call: a scenario that validates does not fail later when the strategy is reset.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from pydantic import ValidationError

from tether.config import format_validation_error
from tether.continuous.exploration.params import TargetsConfig
from tether.continuous.exploration.targets import TargetBook
from tether.errors import ScenarioError
from tether.limits import format_bytes, memory_budget_bytes
from tether.paths.astar import PLANNING_BYTES_PER_CELL, planning_shape
from tether.registry import TARGET_GENERATORS
from tether.world.grid import MAX_CELLS
from tether.world.world import World


def planning_bytes(size_m: np.ndarray, cell_m: float) -> tuple[float, float]:
    """``(cells, bytes)`` of the planning grid of cell ``cell_m`` over ``size_m`` (floats)."""
    with np.errstate(over="ignore"):
        cells = float(np.prod(planning_shape(size_m, cell_m)))
    return cells, cells * PLANNING_BYTES_PER_CELL


def smallest_cell_m(size_m: np.ndarray, budget_bytes: float) -> float:
    """A planning cell (two significant digits) whose grid over ``size_m`` fits the budget."""
    size = np.asarray(size_m, dtype=float)
    cell = (float(np.prod(size)) * PLANNING_BYTES_PER_CELL / budget_bytes) ** (1 / len(size))
    cell = max(cell, 1e-6)
    for _ in range(200):
        digits = 10 ** (math.floor(math.log10(cell)) - 1)
        rounded = math.ceil(cell / digits) * digits
        if planning_bytes(size, rounded)[1] <= budget_bytes:
            return rounded
        cell = rounded * 1.05
    return cell


def check_planning_grid(r_grid_m: float, scenario: Any, world: World) -> None:
    """Refuse an ``r_grid_m`` whose planning grid (built at reset) would not fit.

    The grid may have at most :data:`~tether.world.grid.MAX_CELLS` cells (as a
    scene's grid) and need at most the memory allowance.
    """
    grid = world.grid
    if grid is None:  # nothing to plan on: paths are straight
        return
    cells, need = planning_bytes(grid.size_m, r_grid_m)
    budget = memory_budget_bytes()
    if need <= budget and cells <= MAX_CELLS:
        return
    size = " x ".join(f"{s:g}" for s in grid.size_m)
    if not np.isfinite(need):
        problem = "more cells than can be counted"
    elif need > budget:
        problem = (
            f"{cells:.3g} cells needing about {format_bytes(need)}, more than the "
            f"{format_bytes(budget)} allowed here"
        )
    else:
        problem = f"{cells:.3g} cells, more than the {MAX_CELLS:,} a grid may have"
    fits = smallest_cell_m(grid.size_m, min(budget, MAX_CELLS * PLANNING_BYTES_PER_CELL))
    raise ScenarioError(
        f"{scenario.source}: strategy.params.r_grid_m: planning cells of {r_grid_m:g} m over "
        f"the {size} m world make {problem}; raise strategy.params.r_grid_m to at least "
        f"{fits:g} m (or make the world smaller)"
    )


def target_book(
    targets: TargetsConfig, scenario: Any, world: World, n: int, rng: np.random.Generator
) -> TargetBook:
    """The target queues of ``strategy.params.targets`` (a ``TargetsConfig``) for ``n`` robots.

    Errors name the field: ``strategy.params.targets.params.<field>: ...``.
    """
    field = "strategy.params.targets"
    if targets.kind not in TARGET_GENERATORS:
        raise ScenarioError(
            f"{scenario.source}: {field}.kind: unknown target generator "
            f"{targets.kind!r}; expected one of: {', '.join(TARGET_GENERATORS.names())}"
        )
    gen = TARGET_GENERATORS.get(targets.kind)
    gp = dict(targets.params)
    if targets.kind == "paper_random" and gp.get("config_seed") is None:
        gp["config_seed"] = int(scenario.seed)  # the run seed is the configuration
    try:
        gen_params = gen.Params.model_validate(gp)
    except ValidationError as exc:
        raise ScenarioError(
            format_validation_error(scenario.source, exc, prefix=f"{field}.params")
        ) from None
    try:
        book = TargetBook.empty(n)
        gen.fill(gen_params, book, world, rng)
    except ValueError as exc:  # "height_m: why" names the parameter
        head, sep, rest = str(exc).partition(": ")
        where = f"{field}.params.{head}" if sep and head in gen.Params.model_fields else ""
        raise ScenarioError(
            f"{scenario.source}: {where or field + '.params'}: {rest if where else exc}"
        ) from None
    for robot, queue in enumerate(book.queues):
        for z in queue:
            if len(z.position_m) != world.dim or not world.points_free(z.position_m[None])[0]:
                raise ScenarioError(
                    f"{scenario.source}: {field}: target {z.id} of robot {robot} at "
                    f"{z.position_m.tolist()} is not a free point of the {world.dim}-D world"
                )
    return book
