"""The 3-D town and office of the continuous-connectivity paper (Sec. 4, Figs. 7-8).

Seeded procedural layouts registered in :data:`tether.registry.SCENES`; both
can be sliced to a 2-D floor plan (``dim: 2``). See :mod:`tether.world.scenes`
for the table of all scenes.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from tether.errors import ScenarioError
from tether.registry import SCENES
from tether.world.scene_kit import (
    OFFICE_SIZE_M,
    OUTDOOR_SIZE_M,
    cells_of,
    check_common,
    check_number,
    check_positive,
    check_range,
    check_size,
    fill_pockets,
    raster_box,
    scene_world,
)
from tether.world.world import World


def _partition(
    length: float, block_m: tuple[float, float], street_m: tuple[float, float], rng
) -> list[tuple[float, float]]:
    """Split ``[0, length]`` into blocks separated (and bordered) by streets."""
    spans: list[tuple[float, float]] = []
    cursor = rng.uniform(*street_m)
    while True:
        width = rng.uniform(*block_m)
        if cursor + width + street_m[0] > length:
            width = length - street_m[0] - cursor
            if width >= 0.5 * block_m[0]:
                spans.append((cursor, cursor + width))
            return spans
        spans.append((cursor, cursor + width))
        cursor += width + rng.uniform(*street_m)


def _split(lo: float, hi: float, lot_m: float, rng) -> list[tuple[float, float]]:
    """One or two lots along an axis of a block."""
    if hi - lo < 2 * lot_m:
        return [(lo, hi)]
    cut = lo + (hi - lo) * rng.uniform(0.4, 0.6)
    return [(lo, cut), (cut, hi)]


@SCENES.register("town")
def town(
    rng: np.random.Generator,
    *,
    size_m: Sequence[float] = OUTDOOR_SIZE_M,
    height_m: float = 10.0,
    resolution_m: float = 0.25,
    street_m: Sequence[float] = (4.0, 7.0),
    block_m: Sequence[float] = (8.0, 16.0),
    building_height_m: Sequence[float] = (4.0, 10.0),
    setback_m: float = 1.0,
    empty_lot_p: float = 0.15,
    point_spacing_m: float | None = None,
    dim: int = 3,
    slice_height_m: float = 2.0,
) -> World:
    """Part of a town: box buildings on blocks between streets (Sec. 4.1, Fig. 7).

    The area (default 50 m x 70 m, the paper's) is cut into blocks of
    ``block_m`` length by streets of ``street_m`` width, streets also along
    the border. Each block holds one to four lots; a lot is left empty (a
    square) with probability ``empty_lot_p``, otherwise it gets a box
    building set back up to ``setback_m`` from the lot's edges, with a height
    drawn from ``building_height_m``. Buildings as tall as ``height_m`` cannot
    be flown over. Enclosed free pockets are filled, so all free space is
    connected.

    Parameters
    ----------
    rng
        Source of all randomness.
    size_m
        Extent ``[x, y]`` of the town in m.
    height_m
        Height of the 3-D grid in m; buildings this tall cannot be flown over.
    resolution_m
        Cell size of the grid in m.
    street_m
        ``[min, max]`` street width in m, drawn uniformly.
    block_m
        ``[min, max]`` block length in m, drawn uniformly.
    building_height_m
        ``[min, max]`` building height in m, drawn uniformly.
    setback_m
        A building is set back up to this far from its lot's edges, in m.
    empty_lot_p
        Probability that a lot is left empty (a square).
    point_spacing_m
        Spacing of the obstacle points on building surfaces in m; ``None`` (default)
        keeps one per surface cell, about 8 x 10^4 points for the default town
        (0.5 m gives about 2 x 10^4).
    dim
        3, or 2 for the horizontal slice at ``slice_height_m``.
    slice_height_m
        Height of the 2-D slice in m.
    """
    size = check_size("town", "size_m", size_m, 2)
    height = check_positive("town", "height_m", height_m)
    res = check_positive("town", "resolution_m", resolution_m)
    streets = check_range("town", "street_m", street_m)
    blocks = check_range("town", "block_m", block_m)
    heights = check_range("town", "building_height_m", building_height_m)
    setback_m = check_number("town", "setback_m", setback_m, 0.0, float("inf"))
    empty_lot_p = check_number("town", "empty_lot_p", empty_lot_p, 0.0, 1.0)
    check_common("town", dim, point_spacing_m, slice_height_m)
    occupied = np.zeros(cells_of(np.append(size, height), res, "town"), dtype=bool)
    buildings: list[list[float]] = []
    lot_m = 0.5 * blocks[0]
    for x0, x1 in _partition(size[0], blocks, streets, rng):
        for y0, y1 in _partition(size[1], blocks, streets, rng):
            for lx0, lx1 in _split(x0, x1, lot_m, rng):
                for ly0, ly1 in _split(y0, y1, lot_m, rng):
                    if rng.random() < empty_lot_p:
                        continue
                    back = rng.uniform(0.0, setback_m, size=4)
                    bx0, bx1 = lx0 + back[0], lx1 - back[1]
                    by0, by1 = ly0 + back[2], ly1 - back[3]
                    h = min(rng.uniform(*heights), height)
                    if bx1 - bx0 < res or by1 - by0 < res:
                        continue
                    raster_box(occupied, res, (bx0, by0, 0.0), (bx1, by1, h), True)
                    buildings.append([bx0, by0, bx1, by1, h])
    occupied = fill_pockets(occupied)
    meta = {"scene": "town", "buildings": buildings}
    return scene_world(
        occupied,
        res,
        "town",
        meta,
        dim=dim,
        slice_height_m=slice_height_m,
        point_spacing_m=point_spacing_m,
    )


def _rooms_along(
    y0: float, y1: float, room_m: tuple[float, float], rng
) -> list[tuple[float, float]]:
    """Consecutive room spans along the corridor; the last one takes the rest."""
    spans: list[tuple[float, float]] = []
    cursor = y0
    while y1 - cursor >= 2 * room_m[0]:
        width = min(rng.uniform(*room_m), y1 - cursor - room_m[0])
        spans.append((cursor, cursor + width))
        cursor += width
    spans.append((cursor, y1))
    return spans


@SCENES.register("office")
def office(
    rng: np.random.Generator,
    *,
    size_m: Sequence[float] = OFFICE_SIZE_M,
    height_m: float = 3.0,
    resolution_m: float = 0.1,
    corridor_m: float = 2.0,
    room_m: Sequence[float] = (3.0, 5.0),
    door_m: float = 1.0,
    door_height_m: float = 2.2,
    wall_m: float = 0.2,
    point_spacing_m: float | None = None,
    dim: int = 3,
    slice_height_m: float = 1.0,
) -> World:
    """An office floor: rooms on both sides of a corridor, one door each (Sec. 4.1, Fig. 8).

    The floor (default 10 m x 15 m, the paper's "about 10m x 15m") is closed
    by outer walls. A corridor of width ``corridor_m`` runs along the long
    (y) axis, its centre shifted randomly by up to 0.5 m. On each side,
    partition walls cut rooms of ``room_m`` width; each room has a door of
    width ``door_m`` and height ``door_height_m`` into the corridor, at a
    random place. The default door (1 m) lets the paper's 0.5 m quadrotors
    through with the office's obstacle clearance ``R_o = 0.25 m`` (Table 2).

    ``meta`` holds ``rooms`` and ``doors`` as ``[x0, y0, x1, y1]`` boxes and
    ``corridor`` likewise; ``dim=2`` returns the slice at ``slice_height_m``.

    Parameters
    ----------
    rng
        Source of all randomness.
    size_m
        Extent ``[x, y]`` of the floor in m.
    height_m
        Height of the floor (the ceiling) in m.
    resolution_m
        Cell size of the grid in m.
    corridor_m
        Width of the corridor in m.
    room_m
        ``[min, max]`` room width along the corridor in m, drawn uniformly.
    door_m
        Width of a door in m.
    door_height_m
        Height of a door in m.
    wall_m
        Thickness of a wall in m.
    point_spacing_m
        Spacing of the obstacle points on wall surfaces in m; ``None``: one per
        surface cell.
    dim
        3, or 2 for the horizontal slice at ``slice_height_m``.
    slice_height_m
        Height of the 2-D slice in m.
    """
    size = check_size("office", "size_m", size_m, 2)
    height = check_positive("office", "height_m", height_m)
    res = check_positive("office", "resolution_m", resolution_m)
    corridor = check_positive("office", "corridor_m", corridor_m)
    rooms_range = check_range("office", "room_m", room_m)
    door = check_positive("office", "door_m", door_m)
    door_h = check_positive("office", "door_height_m", door_height_m)
    wall = check_positive("office", "wall_m", wall_m)
    check_common("office", dim, point_spacing_m, slice_height_m)
    width, length = size
    depth = (width - corridor) / 2 - 2 * wall  # room depth on each side
    if depth < door or rooms_range[0] < door + 2 * wall:
        raise ScenarioError(
            f"scene 'office': size_m/corridor_m/room_m: rooms too small for {door} m doors "
            f"(room depth {depth:.2f} m, min room width {rooms_range[0]} m)"
        )
    occupied = np.zeros(cells_of(np.append(size, height), res, "office"), dtype=bool)
    full = (0.0, height)
    # outer walls
    for lo, hi in (
        ((0, 0), (wall, length)),
        ((width - wall, 0), (width, length)),
        ((0, 0), (width, wall)),
        ((0, length - wall), (width, length)),
    ):
        raster_box(occupied, res, (*lo, full[0]), (*hi, full[1]), True)
    cx = width / 2 + rng.uniform(-0.5, 0.5) * min(1.0, depth - door)
    left_x, right_x = cx - corridor / 2, cx + corridor / 2
    rooms: list[list[float]] = []
    doors: list[list[float]] = []
    sides = (
        (left_x - wall, left_x, wall, left_x - wall),
        (right_x, right_x + wall, right_x + wall, width - wall),
    )
    for wall_x0, wall_x1, room_x0, room_x1 in sides:
        raster_box(occupied, res, (wall_x0, 0, 0), (wall_x1, length, height), True)
        spans = _rooms_along(wall, length - wall, rooms_range, rng)
        for k, (y0, y1) in enumerate(spans):
            if k > 0:  # partition wall centred on the boundary
                raster_box(
                    occupied,
                    res,
                    (room_x0, y0 - wall / 2, 0),
                    (room_x1, y0 + wall / 2, height),
                    True,
                )
            inner0 = y0 + (wall / 2 if k > 0 else 0.0)
            inner1 = y1 - (wall / 2 if k < len(spans) - 1 else 0.0)
            rooms.append([room_x0, inner0, room_x1, inner1])
            dy = (
                rng.uniform(inner0 + 0.1, inner1 - 0.1 - door)
                if inner1 - inner0 > door + 0.2
                else inner0
            )
            doors.append([wall_x0, dy, wall_x1, dy + door])
            raster_box(
                occupied, res, (wall_x0 - res, dy, 0), (wall_x1 + res, dy + door, door_h), False
            )
    meta = {
        "scene": "office",
        "rooms": rooms,
        "doors": doors,
        "corridor": [left_x, wall, right_x, length - wall],
        "door_height_m": door_h,
    }
    occupied = fill_pockets(occupied)
    return scene_world(
        occupied,
        res,
        "office",
        meta,
        dim=dim,
        slice_height_m=slice_height_m,
        point_spacing_m=point_spacing_m,
    )
