"""Initial team placements."""

from __future__ import annotations

import numpy as np

from tether.config import InitConfig
from tether.graph import is_connected, pairs_within
from tether.world.world import World


def _default_center(world: World) -> np.ndarray:
    if world.bounds_m is not None:
        return world.bounds_m.mean(axis=0)
    return np.zeros(world.dim)


def random_connected(
    n: int,
    world: World,
    rng: np.random.Generator,
    spacing_m: float,
    min_separation_m: float = 0.0,
    center: np.ndarray | None = None,
    max_tries: int = 200,
) -> np.ndarray:
    """``n`` robots grown one at a time, each within ``spacing_m`` of a random earlier one.

    Every new robot is at least ``min_separation_m`` from all others, in free
    space, and has a clear line of sight to the robot it was placed near, so
    the disc graph of radius ``spacing_m`` is connected by construction.
    """
    center = _default_center(world) if center is None else np.asarray(center, dtype=float)
    if not world.points_free(center[None])[0]:
        raise ValueError("the team's center is inside an obstacle")
    pos = [center]
    while len(pos) < n:
        for _ in range(max_tries):
            anchor = pos[rng.integers(len(pos))]
            direction = rng.normal(size=world.dim)
            direction /= np.linalg.norm(direction)
            radius = spacing_m * rng.uniform(0.3, 1.0)
            cand = anchor + radius * direction
            others = np.asarray(pos)
            if np.min(np.linalg.norm(others - cand, axis=1)) < min_separation_m:
                continue
            if not world.points_free(cand[None])[0]:
                continue
            if not world.segments_clear(anchor[None], cand[None])[0]:
                continue
            pos.append(cand)
            break
        else:
            raise ValueError(
                f"could not place robot {len(pos)} of {n}: the free space near the team is "
                "too small; lower min_separation_m or n_robots, or raise spacing_m"
            )
    return np.asarray(pos)


def uniform_connected(
    n: int,
    world: World,
    rng: np.random.Generator,
    extent_m: np.ndarray,
    range_m: float,
    min_separation_m: float = 0.0,
    center: np.ndarray | None = None,
    max_tries: int = 2000,
) -> np.ndarray:
    """``n`` robots uniform in a box, redrawn until connected within ``range_m``."""
    center = _default_center(world) if center is None else np.asarray(center, dtype=float)
    extent = np.broadcast_to(np.asarray(extent_m, dtype=float), (world.dim,))
    for _ in range(max_tries):
        pos = center + (rng.random((n, world.dim)) - 0.5) * extent
        if not world.points_free(pos).all():
            continue
        if min_separation_m > 0 and len(pairs_within(pos, min_separation_m)):
            continue
        if is_connected(n, pairs_within(pos, range_m)):
            return pos
    raise ValueError(
        f"no connected placement of {n} robots in a box of {extent.tolist()} m found in "
        f"{max_tries} draws; shrink extent_m or raise the sensing range"
    )


def grid_positions(n: int, dim: int, spacing_m: float, center: np.ndarray) -> np.ndarray:
    """A square (2-D) or cubic (3-D) lattice of ``n`` points centred on ``center``."""
    side = int(np.ceil(n ** (1.0 / dim)))
    axes = [np.arange(side) * spacing_m] * dim
    pts = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, dim)[:n]
    return pts - pts.mean(axis=0) + center


def initial_positions(
    cfg: InitConfig, n: int, world: World, rng: np.random.Generator, range_m: float = np.inf
) -> np.ndarray:
    """Place the team as ``cfg`` says (see :class:`tether.config.InitConfig`)."""
    center = None if cfg.center is None else np.asarray(cfg.center, dtype=float)
    if center is not None and len(center) != world.dim:
        raise ValueError(f"center must have {world.dim} coordinates")
    if cfg.kind == "positions":
        if cfg.positions is None:
            raise ValueError("kind 'positions' needs a 'positions' list")
        pos = np.asarray(cfg.positions, dtype=float)
        if pos.ndim != 2 or pos.shape != (n, world.dim):
            raise ValueError(f"positions must be {n} points of {world.dim} coordinates")
        return pos
    if cfg.kind == "grid":
        return grid_positions(
            n, world.dim, cfg.spacing_m, _default_center(world) if center is None else center
        )
    if cfg.kind == "uniform":
        if cfg.extent_m is None or len(cfg.extent_m) not in (1, world.dim):
            raise ValueError(f"kind 'uniform' needs extent_m with {world.dim} side lengths")
        return uniform_connected(
            n, world, rng, np.asarray(cfg.extent_m), range_m, cfg.min_separation_m, center
        )
    return random_connected(n, world, rng, cfg.spacing_m, cfg.min_separation_m, center)
