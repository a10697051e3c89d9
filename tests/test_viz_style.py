"""The one look (style), the run-folder reader, the known-map and box helpers."""

from __future__ import annotations

import json

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pyarrow as pa  # noqa: E402
import pyarrow.parquet as pq  # noqa: E402
import pytest  # noqa: E402
from hypothesis import given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402
from matplotlib.colors import to_rgba  # noqa: E402

from _viewing_helpers import make_run_folder  # noqa: E402
from tether.viewing.known import NEVER, first_seen_by_sight, first_seen_from_maps  # noqa: E402
from tether.viewing.runfolder import frame_indices, load_run  # noqa: E402
from tether.viz import style  # noqa: E402
from tether.viz.boxes import coarsen, greedy_boxes  # noqa: E402
from tether.world.grid import OccupancyGrid  # noqa: E402


def test_link_colours_run_from_red_to_green():
    c = style.link_colours(np.array([0.0, 0.5, 1.0]))
    np.testing.assert_allclose(c[0], to_rgba(style.LINK_BAD), atol=0.01)
    np.testing.assert_allclose(c[2], to_rgba(style.LINK_GOOD), atol=0.01)
    assert c[0, 0] > c[2, 0] and c[2, 1] > c[0, 1] * 0.9
    np.testing.assert_allclose(
        style.link_margin(np.array([0.0, 3.0, 6.0, 9.0]), 6.0), [1.0, 0.5, 0.0, 0.0]
    )


def test_roles_leader_and_connection_colours():
    roles = ["relay", "leader", "explorer", "relay"]
    cmap = style.role_colour_map(roles)
    assert cmap == style.role_colour_map(list(reversed(roles)))  # order-independent
    assert cmap["leader"] == style.LEADER and len(set(cmap.values())) == 3
    assert not {style.LINK_BAD, style.LINK_MID, style.LINK_GOOD} & set(cmap.values())
    cols = style.robot_colours(4, roles=roles, role_map=cmap, leader=0)
    assert tuple(cols[0]) == to_rgba(style.LEADER)  # the leader wins over its role
    assert tuple(cols[2]) == to_rgba(cmap["explorer"])
    conn = style.robot_colours(3, connected=np.array([True, False, True]))
    assert tuple(conn[1]) == to_rgba(style.DISCONNECTED)
    assert tuple(conn[0]) == to_rgba(style.CONNECTED)


def _tower_and_door() -> OccupancyGrid:
    occ = np.zeros((6, 5, 4), dtype=bool)
    occ[1, 1, :3] = True  # a 3-cell tower
    occ[3, :, 2:] = True  # a wall with a passage under it (a door)
    return OccupancyGrid(occ, resolution_m=0.5, origin_m=np.array([10.0, 20.0, 0.0]))


def test_height_map_and_topdown_drawing():
    grid = _tower_and_door()
    heights, ground_free = style.height_map(grid)
    assert heights[1, 1] == pytest.approx(1.5) and heights[3, 2] == pytest.approx(2.0)
    assert heights[0, 0] == 0 and not ground_free[1, 1] and ground_free[3, 2]
    fig, ax = plt.subplots()
    img = style.draw_obstacles_topdown(ax, grid)
    assert img.get_extent() == [10.0, 13.0, 20.0, 22.5]
    assert any(a.get_ylabel() == "obstacle height (m)" for a in fig.axes)
    style.label_axes(ax)
    assert ax.get_xlabel() == "x (m)" and ax.get_ylabel() == "y (m)"
    plt.close(fig)


def test_map_states_tell_unknown_free_and_occupied_apart():
    occ = np.array([[True, False], [False, False]])
    known = np.array([[True, True], [False, False]])
    grid = OccupancyGrid(occ, 1.0)
    states = style.map_states(grid, known)
    assert states.tolist() == [[1, 0], [2, 2]]
    occ[1, 1] = True
    assert style.map_states(OccupancyGrid(occ, 1.0), known)[1, 1] == 3


def test_run_folder_base_station_links_weights_and_missing_rows(tmp_path):
    make_run_folder(tmp_path, n_robots=3, n_steps=4)
    robots = pq.read_table(tmp_path / "robots.parquet").to_pydict()
    keep = [not (s == 2 and r == 1) for s, r in zip(robots["step"], robots["robot"], strict=True)]
    pq.write_table(
        pa.table(
            {k: [v for v, ok in zip(col, keep, strict=True) if ok] for k, col in robots.items()}
        ),
        tmp_path / "robots.parquet",
    )
    # links at a step with no positions are dropped; index 3 (= n_robots) is the base station
    pq.write_table(
        pa.table(
            {
                "step": [0, 0, 1, 7],
                "i": [0, 1, 2, 0],
                "j": [3, 2, 3, 1],
                "weight": [2.0, 1.0, 0.5, 9.0],
            }
        ),
        tmp_path / "links.parquet",
    )
    summary = json.loads((tmp_path / "summary.json").read_text())
    summary["base_m"] = [100.0, 50.0]
    (tmp_path / "summary.json").write_text(json.dumps(summary))
    run = load_run(tmp_path)
    assert run.n_frames == 5 and run.is_exploration
    assert np.isnan(run.positions_m[2, 1]).all() and np.isfinite(run.positions_m[2, 0]).all()
    assert run.links(0).tolist() == [[0, 3], [1, 2]] and len(run.links(4)) == 0
    np.testing.assert_array_equal(run.nodes(1)[3], [100.0, 50.0])
    # weights above 1: divided by the largest kept (the step-7 link was dropped)
    np.testing.assert_allclose(run.link_margins(0), [1.0, 0.5])
    run.link_weights = run.link_weights / 4  # weights in [0, 1] are margins as they are
    np.testing.assert_allclose(run.link_margins(0), [0.5, 0.25])
    assert run.frame_times_s.tolist() == [0.0, 0.5, 1.0, 1.5, 2.0]  # t_s from steps.parquet


def test_frame_indices_keep_the_last_frame():
    assert frame_indices(10, stride=4).tolist() == [0, 4, 8, 9]
    assert frame_indices(10, max_frames=5).tolist() == [0, 2, 4, 6, 8, 9]
    assert frame_indices(3).tolist() == [0, 1, 2]
    assert len(frame_indices(0)) == 0


def test_sight_stops_at_walls_but_sees_them():
    occ = np.zeros((40, 20), dtype=bool)
    occ[20, :] = True  # a wall across the map at x = 20..21 m
    grid = OccupancyGrid(occ, 1.0)
    pos = np.array([[[10.5, 10.5]], [[12.5, 10.5]]])  # (T=2, n=1, 2)
    seen = first_seen_by_sight(grid, pos, range_m=15.0)
    assert seen[10, 10] == 0 and seen[20, 10] == 0  # its own cell and the wall
    assert np.all(seen[21:, :] == NEVER), "saw through the wall"
    assert seen[0, 10] == 0 and seen[26, 10] == NEVER
    assert seen[5, 0] < NEVER


def test_first_seen_from_recorded_maps():
    known = np.zeros((3, 2, 2), dtype=bool)
    known[1, 0, 0] = True
    known[2, :, 0] = True
    fs = first_seen_from_maps(np.array([0, 5, 10]), np.array([0, 5, 10]), known)
    assert fs.tolist() == [[1, NEVER], [2, NEVER]]


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 2**32 - 1), st.floats(0.05, 0.6))
def test_greedy_boxes_cover_exactly_the_occupied_cells(seed, p):
    occ = np.random.default_rng(seed).random((7, 6, 5)) < p
    cover = np.zeros(occ.shape, dtype=int)
    for x0, y0, z0, x1, y1, z1 in greedy_boxes(occ):
        cover[x0:x1, y0:y1, z0:z1] += 1
    np.testing.assert_array_equal(cover, occ.astype(int))


def test_coarsen_is_any_pooling():
    occ = np.zeros((5, 4), dtype=bool)
    occ[4, 3] = True
    assert coarsen(occ, 2).tolist() == [[False, False], [False, False], [False, True]]
