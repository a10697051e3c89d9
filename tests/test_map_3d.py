"""A new user's 3-D building from a floor plan: the 3-D scene tutorial's example, as written.

The block between ``<!-- 3d-map-example -->`` markers is the whole scenario (under 10
lines). It names ``../shared/maps/offices.png`` beside the repository; where that folder
is absent the test runs it on tether's shipped map of the same kind (``office.png``).
Checked against independent oracles: the walls are the map, max-pooled by hand, in every
layer; every robot position recorded over the first 200 steps is inside the building,
in free space and under the ceiling; the paths planned (A* and B-spline, the
strategy's own functions and settings) from each robot's start to its first target stay
under the ceiling in free space. Then the point-cloud scene's floor and ceiling, its
sparse-points warning and the grid rounding.
"""

from __future__ import annotations

import json
import re
import warnings
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest
import yaml
from PIL import Image

from _cli import tether
from tether.errors import TetherWarning
from tether.paths.astar import plan_path, planning_grid
from tether.paths.bspline import smooth_path
from tether.runner import build, run
from tether.world.grid import OccupancyGrid, cells_spanning
from tether.world.scenes import make_scene

ROOT = Path(__file__).resolve().parents[1]
DOC = ROOT / "docs" / "tutorials" / "own-3d-scene.md"
SHIPPED_OFFICE = ROOT / "src" / "tether" / "scenarios" / "maps" / "office.png"


def _doc_scenario() -> tuple[str, dict]:
    text = DOC.read_text()
    block = re.search(r"<!-- 3d-map-example -->\n```yaml\n(.*?)```", text, re.DOTALL).group(1)
    return block, yaml.safe_load(block)


@pytest.fixture
def building(tmp_path, monkeypatch) -> Path:
    """The doc's scenario file, its map found from the repository root (or shipped)."""
    block, data = _doc_scenario()
    monkeypatch.chdir(ROOT)
    path = data["world"]["params"]["path"]
    if not (ROOT / path).exists():
        block = block.replace(path, str(SHIPPED_OFFICE))
    scenario = tmp_path / "my_building.yaml"
    scenario.write_text(block)
    return scenario


def test_the_example_is_short():
    block, data = _doc_scenario()
    assert len(block.strip().splitlines()) < 10
    assert data["world"]["scene"] == "map" and data["world"]["dim"] == 3


def test_the_walls_are_the_map_in_every_layer(building):
    built = build(building)
    grid, params = built.world.grid, yaml.safe_load(building.read_text())["world"]["params"]
    assert grid.dim == 3 and grid.resolution_m == pytest.approx(params["cell_m"])
    np.testing.assert_allclose(built.world.bounds_m[:, 2], [0.0, params["height_m"]])
    image = np.asarray(Image.open(ROOT / params["path"]).convert("L"))
    occupied = (255 - image.astype(float)) / 255 > 0.65  # load_map's default thresholds
    occupied |= ~((255 - image.astype(float)) / 255 < 0.196)
    plan = occupied[::-1].T  # rows top-first -> [ix, iy]
    k = round(params["cell_m"] / params["resolution_m"])
    nx, ny = -(-plan.shape[0] // k), -(-plan.shape[1] // k)
    padded = np.ones((nx * k, ny * k), dtype=bool)
    padded[: plan.shape[0], : plan.shape[1]] = plan
    pooled = padded.reshape(nx, k, ny, k).any(axis=(1, 3))
    for z in range(grid.shape[2]):
        np.testing.assert_array_equal(grid.occupied[:, :, z], pooled)


def test_the_team_and_its_planned_paths_stay_under_the_ceiling(building, tmp_path):
    # the first 200 of the example's 1,531 steps: the team sets out for its targets
    scenario = yaml.safe_load(building.read_text())
    scenario["sim"]["max_steps"] = 200
    out = run(scenario, out_dir=tmp_path / "run", figures=False)
    world = build(building).world
    ceiling = world.bounds_m[1, 2]
    robots = pq.read_table(out.path / "robots.parquet").to_pydict()
    xyz = np.stack([robots["x_m"], robots["y_m"], robots["z_m"]], axis=1)
    assert out.summary["steps"] > 0 and len(xyz) > 0
    assert np.all(world.points_free(xyz)), "a robot left the free space of the building"
    assert xyz[:, 2].max() < ceiling and xyz[:, 2].min() > 0
    events = pq.read_table(out.path / "events.parquet").to_pylist()
    taken = {}
    for e in events:
        if e["kind"] == "target_taken" and e["robot"] not in taken:
            data = json.loads(e["data"]) if isinstance(e.get("data"), str) else e
            taken[e["robot"]] = np.asarray(data["position_m"], dtype=float)
    assert taken, "no robot took a target"
    start = xyz[np.asarray(robots["step"]) == 0]
    cell, inflate = 0.25, 0.5 * (0.25 + 0.6)  # office preset: Rgrid and (Ro + R'o) / 2
    planning = planning_grid(world, cell_m=cell, inflate_m=inflate)
    for robot, goal in taken.items():
        waypoints = plan_path(world, start[robot], goal, cell_m=cell, inflate_m=inflate,
                              planning=planning)  # fmt: skip
        assert waypoints is not None
        spline = smooth_path(waypoints, world, planning=planning)
        points = spline.spline(np.linspace(0.0, 1.0, 400))
        assert points[:, 2].max() < ceiling and points[:, 2].min() > 0
        assert np.all(world.points_free(points))


def test_point_cloud_floor_and_ceiling(tmp_path):
    # two parallel walls 3 m high, sampled every 0.1 m, 4 m apart
    s = np.arange(0.0, 10.0, 0.1)
    z = np.arange(0.0, 3.0 + 1e-9, 0.1)
    wall = np.array([(x, y, h) for x in s for h in z for y in (0.0, 4.0)])
    np.save(tmp_path / "walls.npy", wall)
    world = make_scene("user_points", 0, path=str(tmp_path / "walls.npy"), resolution_m=0.1)
    lo, hi = world.bounds_m
    assert lo[2] == pytest.approx(0.0) and hi[2] == pytest.approx(3.1)  # the top cells' top
    assert lo[0] == pytest.approx(-2.0) and hi[1] == pytest.approx(6.0)  # margin in x, y only
    above = np.array([[5.0, 2.0, 3.5]])
    assert not world.points_free(above)  # nothing above the walls: no way over them
    world = make_scene("user_points", 0, path=str(tmp_path / "walls.npy"), resolution_m=0.1,
                       floor_m=-0.5, ceiling_m=5.0)  # fmt: skip
    assert world.bounds_m[:, 2] == pytest.approx([-0.5, 5.0])
    assert world.points_free(above)


def test_sparse_points_are_warned_about_and_inflated(tmp_path):
    s = np.arange(0.0, 10.0, 0.5)  # a wall sampled every 0.5 m on a 0.1 m grid: gaps
    np.save(tmp_path / "sparse.npy", np.array([(x, 0.0, h) for x in s for h in s[:7]]))
    with pytest.warns(TetherWarning, match=r"points are 0.5 m apart .* inflate_m: 0.25"):
        world = make_scene("user_points", 0, path=str(tmp_path / "sparse.npy"), resolution_m=0.1)
    gap = np.array([[0.25, 0.05, 1.05]])  # between two points of the wall
    assert world.points_free(gap)
    with warnings.catch_warnings():
        warnings.simplefilter("error", TetherWarning)  # inflated enough: no warning
        world = make_scene("user_points", 0, path=str(tmp_path / "sparse.npy"),
                           resolution_m=0.1, inflate_m=0.25)  # fmt: skip
    assert not world.points_free(gap)


def test_grid_size_is_tolerant_of_floating_point():
    assert 484 * 0.1 / 0.1 > 484  # the float product that made 485 cells
    assert cells_spanning(484 * 0.1, 0.1) == 484
    assert cells_spanning(48.41, 0.1) == 485 and cells_spanning(0.01, 0.1) == 1
    grid = OccupancyGrid.from_points(np.array([[1.0, 1.0]]), np.array([[0, 0], [484 * 0.1, 3]]),
                                     0.1)  # fmt: skip
    assert grid.shape == (484, 30)


@pytest.mark.parametrize(
    ("params", "field"),
    [
        ({"dim": 3}, "world.params.height_m"),
        ({"height_m": 3.0}, "world.params.height_m"),
        ({"dim": 3, "height_m": 3.0, "cell_m": 0.25}, "world.params.cell_m"),
        ({"dim": 3, "height_m": 3.0, "resolution_m": 0.01}, "world.params.cell_m"),
    ],
)
def test_bad_3d_map_parameters_name_their_field(building, params, field):
    data = yaml.safe_load(building.read_text())
    data["world"]["params"] = {"path": data["world"]["params"]["path"], "resolution_m": 0.1,
                               **params}  # fmt: skip
    data["world"]["dim"] = params.get("dim", 2)
    building.write_text(yaml.safe_dump(data))
    with pytest.raises(Exception, match=rf"my_building.yaml: {re.escape(field)}: "):
        build(building)


def _refused(capsys, *args: str) -> str:
    code, out, err = tether(capsys, *args)
    assert code == 2 and out == "" and len(err.strip().splitlines()) == 1, err
    return err


def test_a_bounds_error_is_reported_under_bounds_m(capsys, tmp_path):
    np.save(tmp_path / "p.npy", np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 1.0]]))
    (tmp_path / "s.yaml").write_text(
        f"world: {{scene: user_points, dim: 3, params: {{path: {tmp_path / 'p.npy'}, "
        "bounds_m: [[0, 0], [5, 5]]}}\nteam: {n_robots: 1}\nsensing: {range_m: 5}\n"
        "strategy: {name: silent, params: {trajectory: {kind: waypoints, "
        "waypoints: [[0, 0, 0], [1, 0, 0]]}}}\n"
    )
    err = _refused(capsys, "validate", str(tmp_path / "s.yaml"))
    assert "s.yaml: world.params.bounds_m: must be [[lower corner], [upper corner]]" in err


def test_a_start_in_a_wall_or_outside_is_named(capsys, building):
    err = _refused(capsys, "validate", str(building), "--set",
                   "strategy.params.start.center_m=[0.05, 0.05, 1.5]")  # fmt: skip
    assert "strategy.params.start: center_m: [0.05, 0.05, 1.5] is inside an obstacle" in err
    err = _refused(capsys, "validate", str(building), "--set",
                   "strategy.params.start.center_m=[10, 10, 4.0]")  # fmt: skip
    assert "center_m: [10.0, 10.0, 4.0] is outside the world's bounds" in err


def test_a_sensing_range_below_the_link_range_is_refused(capsys, building):
    err = _refused(capsys, "validate", str(building), "--set", "sensing.range_m=2.0")
    assert "sensing.range_m: 2 m is below the strategy's link range Rs = 2.5 m" in err
    err = _refused(capsys, "validate", "connectivity_town", "--set", "sensing.range_m=5.9")
    assert "set sensing.range_m: 6 or lower strategy.params.rs_m" in err
    code, _, err = tether(capsys, "validate", "connectivity_town", "--set",
                          "sensing.range_m=5.9", "--set", "strategy.params.rs_m=5.9")  # fmt: skip
    assert code == 0, err
