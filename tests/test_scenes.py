"""Procedural scenes and scene helpers (tether.world.scenes)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from scipy import ndimage

from tether.errors import MapError, ScenarioError
from tether.registry import SCENES
from tether.world.grid import OccupancyGrid
from tether.world.scenes import free_positions, make_scene
from tether.world.world import World

SHARED_MAPS = Path(__file__).parents[1] / ".." / "shared" / "maps"

# small town for many-seed tests (full-size ones are checked separately)
SMALL_TOWN = {"size_m": (30.0, 40.0), "height_m": 8.0, "resolution_m": 0.5}


def n_free_components(occupied: np.ndarray) -> int:
    return ndimage.label(~occupied)[1]


def brute_surface_cells(occupied: np.ndarray) -> set[tuple[int, ...]]:
    """Occupied cells with a free face-neighbour inside the grid, by plain loops."""
    out = set()
    for cell in zip(*np.nonzero(occupied), strict=True):
        for axis in range(occupied.ndim):
            for step in (-1, 1):
                other = list(cell)
                other[axis] += step
                if 0 <= other[axis] < occupied.shape[axis] and not occupied[tuple(other)]:
                    out.add(tuple(int(c) for c in cell))
    return out


# --------------------------------------------------------------------------- registry


def test_all_scenes_registered() -> None:
    for name in ("free", "empty", "town", "office", "map", "user_points"):
        assert name in SCENES


def test_make_scene_errors_are_one_line() -> None:
    with pytest.raises(ScenarioError, match="unknown; expected one of: .*town"):
        make_scene("towm", 0)
    with pytest.raises(ScenarioError, match=r"sise_m: unknown parameter of scene 'town' "
                       r"\(did you mean 'size_m'\?\).*\(accepted: size_m"):  # fmt: skip
        make_scene("town", 0, sise_m=3)
    with pytest.raises(ScenarioError, match="resolution_m: must be a positive number"):
        make_scene("town", 0, resolution_m=-1)
    with pytest.raises(ScenarioError, match="street_m"):
        make_scene("town", 0, street_m=(5, 2))
    with pytest.raises(ScenarioError, match="too small"):
        make_scene("office", 0, door_m=5.0)
    bad = [
        ("free", {"dim": 2, "bounds_m": [[0, 0], [-1, 5]]}, "bounds_m"),
        ("free", {"dim": 2, "bounds_m": [[0, 0], [1]]}, "bounds_m"),
        ("free", {"dim": 4}, "dim"),
        ("town", {"empty_lot_p": 2}, "empty_lot_p: must be a number in [0.0, 1.0]"),
        ("town", {"size_m": ["a", 3]}, "size_m: must be 2 positive numbers"),
        ("town", {"dim": 2, "slice_height_m": 20.0}, "slice_height_m: must be below"),
        ("office", {"dim": 1}, "dim: must be 2 or 3"),
        ("office", {"point_spacing_m": 0}, "point_spacing_m"),
    ]
    for name, params, text in bad:
        with pytest.raises(ScenarioError) as exc:
            make_scene(name, 0, **params)
        message = str(exc.value)
        assert "\n" not in message and f"scene {name!r}" in message and text in message, message


# --------------------------------------------------------------------------- surface points


@pytest.mark.parametrize("seed", range(6))
def test_surface_points_match_brute_force(seed: int) -> None:
    rng = np.random.default_rng(seed)
    dim = 2 + seed % 2
    shape = tuple(rng.integers(3, 9, size=dim))
    occupied = rng.random(shape) < 0.5
    grid = OccupancyGrid(occupied, float(rng.uniform(0.1, 2)), rng.normal(size=dim))
    points = grid.surface_points()
    got = {tuple(int(c) for c in cell) for cell in grid.to_cell(points)}
    assert got == brute_surface_cells(occupied)
    assert len(points) == len(got)
    # thinning keeps one surface cell per block, covering every block that has one
    stride = 2
    thin = grid.surface_points(spacing_m=stride * grid.resolution_m)
    thin_cells = grid.to_cell(thin)
    assert {tuple(c) for c in thin_cells} <= got
    assert {tuple(c // stride) for c in thin_cells} == {tuple(np.array(c) // stride) for c in got}
    assert len(thin) == len({tuple(c // stride) for c in thin_cells})


# --------------------------------------------------------------------------- free


def test_free_scene_2d_and_3d() -> None:
    world = make_scene("free", 0)
    assert world.dim == 2 and world.bounds_m is None and not world.has_obstacles
    with pytest.raises(ScenarioError, match="unbounded"):
        free_positions(world, 3, np.random.default_rng(0))
    bounds = [[-1.0, 2.0, 0.0], [4.0, 5.0, 3.0]]
    world3 = make_scene("free", 0, dim=3, bounds_m=bounds)
    assert world3.dim == 3
    pts = free_positions(world3, 500, np.random.default_rng(1))
    assert pts.shape == (500, 3)
    assert world3.points_free(pts).all()


# --------------------------------------------------------------------------- paper scenes


def test_paper_sizes() -> None:
    # "50m x 70m for both the empty space and the town, and about 10m x 15m for
    # the office" (continuous-connectivity paper, Sec. 4.1)
    empty = make_scene("empty", 0)
    assert empty.dim == 3 and not empty.has_obstacles and len(empty.obstacle_points) == 0
    np.testing.assert_allclose(empty.bounds_m[1, :2] - empty.bounds_m[0, :2], [50, 70])
    town = make_scene("town", 0)
    np.testing.assert_allclose(town.bounds_m[1, :2] - town.bounds_m[0, :2], [50, 70])
    assert town.grid.resolution_m == 0.25
    assert 1e4 <= len(town.obstacle_points) <= 1e5
    office = make_scene("office", 0)
    np.testing.assert_allclose(office.bounds_m[1, :2] - office.bounds_m[0, :2], [10, 15])
    assert office.grid.resolution_m == 0.1
    for world in (empty, town, office):
        assert world.grid.dim == 3
        assert np.all(world.bounds_m[0] == 0) and world.bounds_m[1, 2] > 2.0


@pytest.mark.parametrize(
    ("name", "params"),
    [
        ("town", SMALL_TOWN),
        ("office", {}),
        ("town", {**SMALL_TOWN, "dim": 2}),
        ("office", {"dim": 2}),
    ],
)
def test_scenes_deterministic_and_seed_dependent(name: str, params: dict) -> None:
    worlds = [make_scene(name, seed, **params) for seed in (5, 5, 6)]
    np.testing.assert_array_equal(worlds[0].grid.occupied, worlds[1].grid.occupied)
    np.testing.assert_array_equal(worlds[0].obstacle_points, worlds[1].obstacle_points)
    assert worlds[0].meta == worlds[1].meta
    assert not np.array_equal(worlds[0].grid.occupied, worlds[2].grid.occupied)


@pytest.mark.parametrize("seed", range(8))
@pytest.mark.parametrize(
    ("name", "params"),
    [
        ("town", SMALL_TOWN),
        ("office", {}),
        ("town", {**SMALL_TOWN, "dim": 2}),
        ("office", {"dim": 2}),
    ],
)
def test_scene_invariants(name: str, params: dict, seed: int) -> None:
    world = make_scene(name, seed, **params)
    grid = world.grid
    assert world.dim == grid.dim == params.get("dim", 3)
    points = world.obstacle_points
    assert len(points) > 0 and points.shape[1] == world.dim
    assert grid.is_occupied(points).all()  # every obstacle point is in an occupied cell
    # all free space is one face-connected region (no sealed pockets)
    assert n_free_components(grid.occupied) == 1
    fraction = grid.occupied.mean()
    assert 0.02 < fraction < 0.6
    rng = np.random.default_rng(seed)
    clearance = 0.25 if name == "office" else 0.75  # R_o of the paper's Table 2
    pts = free_positions(world, 200, rng, clearance)
    assert world.points_free(pts, clearance).all()
    assert (world.clearance_m(pts) >= clearance).all()


@pytest.mark.parametrize("seed", range(10))
def test_office_doors_make_every_room_reachable(seed: int) -> None:
    world = make_scene("office", seed)
    grid, meta = world.grid, world.meta
    res = grid.resolution_m
    robot_height_m, robot_radius_m = 1.0, 0.25  # the paper's 0.5 m quadrotors
    iz = int(robot_height_m / res)
    assert robot_height_m < meta["door_height_m"]

    def components(occupied_slice: np.ndarray) -> tuple[np.ndarray, list[int]]:
        # free cells where the robot's disc fits, labelled with 4-connectivity
        fits = ndimage.distance_transform_edt(~occupied_slice) * res > robot_radius_m
        labels, _ = ndimage.label(fits)
        centres = [*meta["rooms"], meta["corridor"]]
        cells = [((x0 + x1) / 2 / res, (y0 + y1) / 2 / res) for x0, y0, x1, y1 in centres]
        return labels, [int(labels[int(cx), int(cy)]) for cx, cy in cells]

    slice_ = grid.occupied[:, :, iz]
    _, ids = components(slice_)
    assert len(meta["rooms"]) >= 4
    assert 0 not in ids  # every room centre has room for the robot
    assert len(set(ids)) == 1  # ... and all are in the corridor's component
    # control: with the doors bricked up, no room reaches the corridor
    closed = slice_.copy()
    for x0, y0, x1, y1 in meta["doors"]:
        closed[int(np.floor(x0 / res)) - 1 : int(np.ceil(x1 / res)) + 1,
               int(np.floor(y0 / res)) : int(np.ceil(y1 / res)) + 1] = True  # fmt: skip
    _, closed_ids = components(closed)
    assert len(set(closed_ids)) == len(closed_ids)
    # doors are at least as wide as asked, and the wall above a door is solid
    for x0, y0, x1, y1 in meta["doors"]:
        assert y1 - y0 >= 1.0 - 1e-9
        above = grid.occupied[int((x0 + x1) / 2 / res), int((y0 + y1) / 2 / res)]
        assert above[int(2.5 / res)] and not above[iz]


def test_town_buildings_and_streets() -> None:
    world = make_scene("town", 3)
    grid = world.grid
    res, height = grid.resolution_m, grid.size_m[2]
    buildings = np.asarray(world.meta["buildings"])
    assert len(buildings) >= 10
    assert np.all(buildings[:, 4] <= height)
    for x0, y0, x1, y1, h in buildings:
        inside = np.array([[(x0 + x1) / 2, (y0 + y1) / 2, h / 2]])
        above = inside + [0, 0, h / 2 + res]
        assert grid.is_occupied(inside)[0]
        assert above[0, 2] >= height or not grid.is_occupied(above)[0]
    # a full-size town is one connected free space, with plenty of it at flight height
    assert n_free_components(grid.occupied) == 1
    pts = free_positions(world, 300, np.random.default_rng(0), clearance_m=0.75)
    assert world.points_free(pts, 0.75).all()
    footprint = grid.occupied[:, :, 0].mean()
    assert 0.1 < footprint < 0.6


# --------------------------------------------------------------------------- free_positions


def test_free_positions_uniform_over_free_cells() -> None:
    occupied = np.zeros((40, 10), dtype=bool)
    occupied[:20] = True  # left half blocked
    world = World(dim=2, grid=OccupancyGrid(occupied, 0.5, (1.0, 2.0)))
    rng = np.random.default_rng(0)
    pts = free_positions(world, 4000, rng)
    assert world.points_free(pts).all()
    # uniform on x in [11, 21]: mean 16, sd 10/sqrt(12)/sqrt(n)
    assert abs(pts[:, 0].mean() - 16.0) < 4 * (10 / np.sqrt(12) / np.sqrt(4000))
    assert abs(pts[:, 1].mean() - 4.5) < 4 * (5 / np.sqrt(12) / np.sqrt(4000))
    again = free_positions(world, 4000, np.random.default_rng(0))
    np.testing.assert_array_equal(pts, again)


def test_free_positions_same_component_and_errors() -> None:
    occupied = np.zeros((30, 10), dtype=bool)
    occupied[10] = True  # wall: a 10-cell and a 19-cell region
    world = World(dim=2, grid=OccupancyGrid(occupied, 1.0))
    pts = free_positions(world, 300, np.random.default_rng(2), same_component=True)
    assert (pts[:, 0] > 11).all()
    pts = free_positions(world, 300, np.random.default_rng(2))
    assert (pts[:, 0] < 10).any() and (pts[:, 0] > 11).any()
    with pytest.raises(ScenarioError, match="no free cell with clearance 50"):
        free_positions(world, 1, np.random.default_rng(0), clearance_m=50.0)


# --------------------------------------------------------------------------- map scene


def test_map_scene_from_image(tmp_path: Path) -> None:
    pixels = np.full((6, 8), 255, dtype=np.uint8)
    pixels[1:3, 2:6] = 0
    Image.fromarray(pixels).save(tmp_path / "m.png")
    world = make_scene("map", 0, path=str(tmp_path / "m.png"), resolution_m=0.5)
    assert world.dim == 2
    np.testing.assert_allclose(world.bounds_m, [[0, 0], [4, 3]])
    assert world.grid.occupied.sum() == 8
    assert world.grid.is_occupied(world.obstacle_points).all()
    with pytest.raises(MapError, match="file not found"):
        make_scene("map", 0, path=str(tmp_path / "nope.png"))


@pytest.mark.parametrize("name", ["grass", "offices", "open"])
def test_map_scene_shared_maps(name: str) -> None:
    path = SHARED_MAPS / f"{name}.png"
    if not path.is_file():
        pytest.skip(f"shared test maps not available ({SHARED_MAPS} is absent)")
    world = make_scene("map", 0, path=str(path), resolution_m=0.1)
    np.testing.assert_allclose(world.bounds_m, [[0, 0], [80, 60]])
    assert world.grid.is_occupied(world.obstacle_points).all()
    # boundary cells only: far fewer points than occupied cells
    assert 0 < len(world.obstacle_points) < world.grid.occupied.sum()
    pts = free_positions(world, 100, np.random.default_rng(0), 0.5, same_component=True)
    assert world.points_free(pts, 0.5).all()


# --------------------------------------------------------------------------- user points


def write_points(folder: Path, points: np.ndarray) -> list[Path]:
    np.save(folder / "p.npy", points)
    header = "x,y,z" if points.shape[1] == 3 else "x,y"
    np.savetxt(folder / "p.csv", points, delimiter=",", header=header, comments="")
    np.savetxt(folder / "p.xyz", points, header="a comment")
    return [folder / "p.npy", folder / "p.csv", folder / "p.xyz"]


@pytest.mark.parametrize("dim", [2, 3])
def test_user_points_formats_agree(dim: int, tmp_path: Path) -> None:
    rng = np.random.default_rng(dim)
    points = rng.uniform(-5, 5, size=(300, dim))
    worlds = [
        make_scene("user_points", 0, path=str(p), resolution_m=0.5)
        for p in write_points(tmp_path, points)
    ]
    for world in worlds:
        assert world.dim == dim
        np.testing.assert_allclose(world.obstacle_points, points, atol=1e-12)
        np.testing.assert_array_equal(world.grid.occupied, worlds[0].grid.occupied)
        assert world.grid.is_occupied(points).all()
        assert world.in_bounds(points).all()
    # occupied cells are exactly the cells holding a point
    cells = {tuple(c) for c in worlds[0].grid.to_cell(points)}
    assert cells == {tuple(c) for c in np.argwhere(worlds[0].grid.occupied)}


def test_user_points_bounds_drop_points(tmp_path: Path) -> None:
    points = np.array([[1.0, 1.0], [2.0, 2.0], [50.0, 50.0]])
    np.save(tmp_path / "p.npy", points)
    world = make_scene("user_points", 0, path=str(tmp_path / "p.npy"), bounds_m=[[0, 0], [10, 10]])
    assert len(world.obstacle_points) == 2 and world.meta["dropped_points"] == 1
    np.testing.assert_allclose(world.bounds_m, [[0, 0], [10, 10]])


BAD_POINT_FILES = [
    ("p.npy", None, "file not found"),
    ("p.txt", "1 2\n", "unsupported points file type '.txt'"),
    ("p.csv", "x,y\n1,2\n3,oops\n", "line 3: expected 2 or 3 numbers separated by commas"),
    ("p.csv", "1,2\n3,4,5\n", "line 2: expected 2 numbers"),
    ("p.xyz", "1 2 3 4\n", "line 1: expected 2 or 3 numbers separated by spaces (got 4)"),
    ("p.xyz", "# only a comment\n", "holds no points"),
    ("p.xyz", "1 nan\n", "not finite"),
    ("p.npy", b"garbage", "not a readable .npy array"),
]


@pytest.mark.parametrize(("name", "content", "text"), BAD_POINT_FILES)
def test_user_points_bad_files(name: str, content, text: str, tmp_path: Path) -> None:
    path = tmp_path / name
    if isinstance(content, str):
        path.write_text(content)
    elif content is not None:
        path.write_bytes(content)
    with pytest.raises(MapError) as exc:
        make_scene("user_points", 0, path=str(path))
    message = str(exc.value)
    assert "\n" not in message and name in message and text in message, message


def test_user_points_bad_arrays_and_bounds(tmp_path: Path) -> None:
    np.save(tmp_path / "wide.npy", np.zeros((4, 5)))
    with pytest.raises(MapError, match=r"wide.npy: must be an array of x y \[z\] rows"):
        make_scene("user_points", 0, path=str(tmp_path / "wide.npy"))
    np.save(tmp_path / "ok.npy", np.ones((4, 2)))
    with pytest.raises(MapError, match="ok.npy: bounds_m: must be"):
        make_scene("user_points", 0, path=str(tmp_path / "ok.npy"), bounds_m=[[0, 0, 0], [1, 1, 1]])
    with pytest.raises(MapError, match="ok.npy: bounds_m: none of the 4 points"):
        make_scene("user_points", 0, path=str(tmp_path / "ok.npy"), bounds_m=[[5, 5], [9, 9]])


def test_seed_parameter_fixes_the_layout_independently_of_the_run_seed() -> None:
    a = make_scene("town", 1, seed=7, size_m=(30.0, 30.0), resolution_m=0.5)
    b = make_scene("town", 2, seed=7, size_m=(30.0, 30.0), resolution_m=0.5)
    c = make_scene("town", 7, size_m=(30.0, 30.0), resolution_m=0.5)
    d = make_scene("town", 1, size_m=(30.0, 30.0), resolution_m=0.5)
    assert np.array_equal(a.grid.occupied, b.grid.occupied)
    assert np.array_equal(a.grid.occupied, c.grid.occupied)
    assert not np.array_equal(a.grid.occupied, d.grid.occupied)
    with pytest.raises(ScenarioError, match="seed must be a non-negative int"):
        make_scene("town", 1, seed=-1)
