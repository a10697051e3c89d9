"""Scaffolding shared by the exploration-simulator tests (not a test module)."""

from __future__ import annotations

import numpy as np

from tether.recurrent.exploration.sim import ExplorationSim


def office(seed: int = 0, size: tuple[float, float] = (12.0, 16.0)) -> np.ndarray:
    """Occupancy of a procedural 2-D office floor (True = obstacle)."""
    import tether.world.scenes  # noqa: F401  (registers the scenes)
    from tether.registry import SCENES

    world = SCENES.get("office")(np.random.default_rng(seed), dim=2, size_m=list(size))
    return world.grid.occupied


class Idle:
    """A strategy that never plans (the test drives the robots)."""

    name = "idle"

    def start(self, sim: ExplorationSim) -> None:
        pass

    def update(self, sim: ExplorationSim) -> None:
        pass

    def metrics(self) -> dict:
        return {}


def farthest_known_path(sim: ExplorationSim, robot: int) -> list:
    """The path, on the BS's coarse known map, from ``robot`` to the farthest reachable cell."""
    coarse = sim.coarse_known()
    src = int(coarse.node_at(sim.pos[robot])[0])
    d, pred = coarse.distances([src], predecessors=True)
    dst = int(np.nanargmax(np.where(np.isfinite(d[0]), d[0], -1)))
    return coarse.path(pred[0], dst)
