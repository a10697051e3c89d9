"""What each robot observes: its own state, its task vector, its sensed neighbours, its map.

One agent's observation is a flat ``float32`` vector (``dim`` = 2 or 3, ``K`` =
``max_neighbours``, ``r`` = ``map_patch_cells``)::

    [0 : dim)              own velocity / max_speed_mps
    [dim : 2 dim)          own position minus the team's start centroid, / link range
    [2 dim : 3 dim)        task vector (to the leader's carrot, goal, target or base
                           station), / link range
    [3 dim]                1 if the robot has a task vector, else 0
    then K slots of dim+2  a sensed neighbour, nearest first: its relative position as
                           measured (with the scenario's sensing noise) / link range, its
                           link margin 1 - distance / link range, and 1 (an empty slot
                           is all 0)
    then (2r+1)^dim        occupancy of the cells around the robot (1 occupied or outside
                           the map, 0 free), cells of the map's resolution, C order

Neighbours are what the robot senses (range, line of sight, occlusion by robot bodies),
base stations included.
"""

from __future__ import annotations

import numpy as np

from tether.sensing import Observation
from tether.world.world import World

#: every observation element lies in [-OBS_LIMIT, OBS_LIMIT] (positions are in link ranges)
OBS_LIMIT = 1e5


def obs_size(dim: int, max_neighbours: int, patch_cells: int) -> int:
    """Length of one agent's observation vector."""
    return (
        3 * dim + 1 + max_neighbours * (dim + 2) + (2 * patch_cells + 1) ** dim * (patch_cells > 0)
    )


def neighbour_slots(obs: Observation, n: int, k: int, range_m: float) -> np.ndarray:
    """``(n, k, dim + 2)``: the ``k`` nearest sensed neighbours of robots ``0..n-1``."""
    dim = obs.measured.shape[1] if obs.measured.ndim == 2 else 0
    out = np.zeros((n, k, dim + 2))
    if k == 0 or len(obs.measured) == 0:
        return out
    observer = obs.observer()
    dist = np.sqrt(np.einsum("kd,kd->k", obs.measured, obs.measured))
    order = np.lexsort((dist, observer))
    rank = np.arange(len(order)) - obs.indptr[observer[order]]
    keep = (rank < k) & (observer[order] < n)
    rows, slots = observer[order][keep], rank[keep]
    picked = order[keep]
    out[rows, slots, :dim] = obs.measured[picked] / range_m
    out[rows, slots, dim] = 1.0 - dist[picked] / range_m
    out[rows, slots, dim + 1] = 1.0
    return out


def map_patch(world: World, q: np.ndarray, cells: int) -> np.ndarray:
    """``(n, (2 cells + 1)^dim)`` occupancy around each robot (1: occupied or off the map)."""
    n, dim = q.shape
    side = 2 * cells + 1
    if world.grid is None:
        out = np.zeros((n, side**dim))
        if world.bounds_m is None:
            return out
        res = 1.0
    else:
        res = world.grid.resolution_m
    axes = np.meshgrid(*[np.arange(-cells, cells + 1) * res] * dim, indexing="ij")
    offsets = np.stack(axes, axis=-1).reshape(-1, dim)
    points = (q[:, None, :] + offsets[None]).reshape(-1, dim)
    return (~world.points_free(points)).reshape(n, -1).astype(float)


def observations(
    obs: Observation,
    positions: np.ndarray,
    velocities: np.ndarray,
    origin: np.ndarray,
    task: tuple[np.ndarray, np.ndarray],
    *,
    max_speed_mps: float,
    range_m: float,
    max_neighbours: int,
    world: World,
    patch_cells: int,
) -> np.ndarray:
    """``(n, obs_size)`` float32: every agent's observation (module docstring)."""
    n, dim = positions.shape
    offsets, flags = task
    parts = [
        velocities / max_speed_mps,
        (positions - origin) / range_m,
        offsets / range_m,
        flags[:, None],
        neighbour_slots(obs, n, max_neighbours, range_m).reshape(n, -1),
    ]
    if patch_cells > 0:
        parts.append(map_patch(world, positions, patch_cells))
    out = np.concatenate(parts, axis=1)
    return np.clip(out, -OBS_LIMIT, OBS_LIMIT).astype(np.float32)
