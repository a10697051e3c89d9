"""Scenario values that pass their field's bounds but that a recurrent run cannot run.

:func:`tether.recurrent.strategy._config` turns metres into cells; these checks
refuse, with one line naming the field and the fix, what would later fail
inside the simulator (a robot that never moves, a base station that knows no
cell to plan from, a coarse cell wider than the map).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from tether.errors import ScenarioError
from tether.sensing.depth import cast_rays

#: ``round(metres / resolution_m, 9)``: a value in cells is a multiple of this
CELL_QUANTUM = 1e-9
#: ``ExplorationSim._move`` advances a robot only while its budget exceeds 1e-9 cells
MIN_STEP_CELLS = 2e-9
#: samples of one full depth scan (rays x samples per ray) a scenario may ask for
MAX_RAY_SAMPLES = 4_000_000


def coarse_factor(params: Any, scenario: Any, resolution_m: float, shape: Any) -> int:
    """``round(coarse_cell_m / resolution_m)``, refused when wider than the map.

    Without ``shape`` the factor is only bounded by 1 (no map to compare with).
    """
    ratio = params.coarse_cell_m / resolution_m
    if shape is None:
        return max(int(round(ratio)), 1) if np.isfinite(ratio) else 1
    side = int(min(shape))
    if not ratio < side + 0.5:  # also inf / nan from a tiny resolution_m
        raise ScenarioError(
            f"{scenario.source}: strategy.params.coarse_cell_m: {params.coarse_cell_m:g} m is "
            f"{ratio:.3g} cells of {resolution_m:g} m, wider than the map "
            f"({shape[0]} x {shape[1]} cells); use at most {side * resolution_m:g} m "
            "(or a larger world.params.resolution_m)"
        )
    return max(int(round(ratio)), 1)


def check_speed(params: Any, scenario: Any, resolution_m: float, speed_cells: float) -> None:
    """A speed that moves a robot less than the simulator's 1e-9 cells per step."""
    if speed_cells >= MIN_STEP_CELLS:
        return
    least = MIN_STEP_CELLS * resolution_m / scenario.sim.dt_s
    raise ScenarioError(
        f"{scenario.source}: strategy.params.speed_m_s: {params.speed_m_s:g} m/s is "
        f"{speed_cells:g} cells of {resolution_m:g} m per {scenario.sim.dt_s:g} s step, "
        f"so no robot would move; use at least {least:.3g} m/s"
    )


def check_ref_distance(params: Any, scenario: Any, resolution_m: float, cells: float) -> None:
    """The signal model's reference distance must be a positive number of cells."""
    if params.link_model != "signal" or cells > 0:
        return
    least = CELL_QUANTUM * resolution_m
    raise ScenarioError(
        f"{scenario.source}: strategy.params.signal.ref_distance_m: "
        f"{params.signal.ref_distance_m:g} m rounds to 0 cells of {resolution_m:g} m; "
        f"use at least {least:.3g} m"
    )


def _covers(factor: int, range_cells: float, resolution_deg: float) -> bool:
    """Whether a full scan from a free coarse cell's centre sees all its fine cells.

    The same rays as the run's first scan (heading 0, 360 degrees, samples every
    half cell): the block is free, so no ray stops inside it, and a ray that
    leaves the convex block never comes back, so the cells around do not matter.
    """
    block = np.zeros((factor, factor), dtype=bool)
    origin = np.full((1, 2), factor / 2.0)
    seen = cast_rays(block, origin, np.zeros(1), 2 * np.pi, range_cells, np.radians(resolution_deg))
    return bool(np.unique(seen[0]).size == factor * factor)


def check_base_sensed(
    params: Any, scenario: Any, resolution_m: float, factor: int, range_cells: float
) -> None:
    """The first scan must make the base station's coarse cell known.

    Robot 0 starts on the BS's coarse cell centre and scans 360 degrees; the BS
    plans on the coarse cells whose fine cells are all known, so a range too
    short to see its own ``factor x factor`` block leaves it nothing to plan from.
    """
    # samples beyond half the block's diagonal are outside it: cap the work there
    reach = np.ceil(factor / np.sqrt(2.0) / 0.5) * 0.5 + 0.5
    if _covers(factor, min(range_cells, reach), params.sensor_resolution_deg):
        return
    field = f"{scenario.source}: sensing.range_m"
    what = (
        f"{scenario.sensing.range_m:g} m ({range_cells:g} cells of {resolution_m:g} m) does "
        f"not see the base station's own coarse cell ({factor} x {factor} cells, "
        f"coarse_cell_m = {params.coarse_cell_m:g} m) in the first scan, so it has no "
        "known cell to plan from"
    )
    rays = int(np.ceil(360.0 / params.sensor_resolution_deg)) + 1
    top = min(reach, np.floor(MAX_RAY_SAMPLES / rays - 1) * 0.5)  # the longest scan allowed
    if top <= range_cells or not _covers(factor, top, params.sensor_resolution_deg):
        raise ScenarioError(
            f"{field}: {what}; lower strategy.params.coarse_cell_m or "
            "strategy.params.sensor_resolution_deg"
        )
    # samples are every half cell: the least range is a multiple of 0.5 cells
    lo, hi = int(range_cells / 0.5), int(round(top / 0.5))  # lo fails, hi covers
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if _covers(factor, mid * 0.5, params.sensor_resolution_deg):
            hi = mid
        else:
            lo = mid
    least = hi * 0.5 * resolution_m
    raise ScenarioError(
        f"{field}: {what}; use at least {least:g} m ({hi * 0.5:g} cells) or a smaller "
        "strategy.params.coarse_cell_m"
    )
