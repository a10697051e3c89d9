"""A 3-D scene of your own: a hall with pillars, registered as the scene ``pillars``.

Run it:  tether run examples/pillar_hall.yaml --plugin examples/pillars_scene.py
or       python examples/pillars_scene.py
A scene is a function ``(rng, **params) -> World``: every random choice comes from
``rng`` (the run's seed, or ``world.params.seed``), and every keyword parameter is a
key of the scenario's ``world.params``, documented in the Parameters section.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tether.registry import SCENES
from tether.runner import run
from tether.world import OccupancyGrid, World

HALL = Path(__file__).with_name("pillar_hall.yaml")


@SCENES.register("pillars")
def pillars(
    rng: np.random.Generator, *, count: int = 12, height_m: float = 6.0, resolution_m: float = 0.25
) -> World:
    """A 30 m x 30 m hall with ``count`` square pillars at random places.

    Parameters
    ----------
    rng
        Source of all randomness.
    count
        Number of pillars (1 m x 1 m, floor to ceiling), at least 6 m from the walls.
    height_m
        Height of the hall: the ceiling, in m.
    resolution_m
        Cell size of the occupancy grid, in m.
    """
    cells = round(30.0 / resolution_m)
    occupied = np.zeros((cells, cells, round(height_m / resolution_m)), dtype=bool)
    half = round(0.5 / resolution_m)
    for x, y in rng.integers(round(6.0 / resolution_m), cells - round(6.0 / resolution_m),
                             size=(count, 2)):  # fmt: skip
        occupied[x - half : x + half, y - half : y + half, :] = True
    grid = OccupancyGrid(occupied, resolution_m, np.zeros(3))
    # the obstacle points of the connectivity force: the pillars' surface cells
    return World(dim=3, grid=grid, obstacle_points=grid.surface_points(), name="pillars")


def main(out_dir: str = "runs/pillar_hall") -> dict:
    outcome = run(HALL, out_dir=out_dir)
    print(f"connected all steps: {outcome.summary['connected_all_steps']}; in {outcome.path}")
    return outcome.summary


if __name__ == "__main__":
    main()
