"""Workspaces: occupancy grids, map files and procedural scenes."""

from __future__ import annotations

from tether.world.grid import OccupancyGrid
from tether.world.world import World

__all__ = ["OccupancyGrid", "World"]
