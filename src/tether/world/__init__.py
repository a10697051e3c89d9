"""Workspaces: occupancy grids, map files and procedural scenes.

Importing this package registers the built-in scenes in ``tether.registry.SCENES``.
"""

from __future__ import annotations

from tether.world.grid import OccupancyGrid
from tether.world.maps import load_map, save_map
from tether.world.scenes import free_positions, make_scene
from tether.world.world import World

__all__ = ["OccupancyGrid", "World", "free_positions", "load_map", "make_scene", "save_map"]
