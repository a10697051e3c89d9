"""The team placement ``random_connected`` as it was before it became O(n log n).

Kept as the reference the new placement is tested against (the same properties,
the same statistics):
robots grown one at a time, each within ``spacing_m`` of a uniformly random
earlier robot, at least ``min_separation_m`` from all others, in free space,
with a clear line of sight to its anchor. Every candidate is checked against
all robots placed so far, so placing ``n`` robots costs O(n^2) or worse.
"""

from __future__ import annotations

import numpy as np

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
