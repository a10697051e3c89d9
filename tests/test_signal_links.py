"""The ``signal`` link model against values computed by hand, and the planner's use of it.

Defaults: P(d, w) = -40 dBm - 25 log10(max(d, 10) / 10) - 3 dB * w, linked when P >= -70 dBm.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from tether.recurrent.planning.expgraph import GraphBuilder
from tether.registry import LINK_MODELS
from tether.sensing.links import SignalLinks, link_pairs
from tether.world.los import cells_crossed


def test_registered_beside_los_and_disk() -> None:
    import tether.sensing.links  # noqa: F401

    assert {"los", "disk", "signal"} <= set(LINK_MODELS.names())
    model = LINK_MODELS.get("signal")(wall_loss_db=5.0)
    assert isinstance(model, SignalLinks) and model.wall_loss_db == 5.0


def test_cells_crossed_by_hand() -> None:
    walls = np.zeros((20, 10), dtype=bool)
    walls[5:7, :] = True  # a wall two cells thick, x = 5 and 6
    a = [[0.5, 0.5], [0.5, 0.5], [3.0, 3.0], [8.0, 8.0], [0.5, 2.5], [-2.5, 0.5], [4.5, 4.5]]
    b = [[10.5, 0.5], [4.5, 0.5], [8.0, 8.0], [3.0, 3.0], [10.5, 5.5], [1.5, 0.5], [4.5, 4.5]]
    # horizontal through the wall: 2; stopping before it: 0; the diagonal through
    # corners (3,3)-(8,8) enters (3,3) (4,4) (5,5) (6,6) (7,7) only: 2, either way;
    # slope 0.3 from (0.5, 2.5): y = 3.85 at x = 5, y = 4 at x = 5.5, y = 4.45 at
    # x = 7, so it enters (5, 3), (5, 4), (6, 4): 3; three cells left of the grid
    # count as walls: 3; a point in a free cell: 0
    assert cells_crossed(walls, a, b).tolist() == [2, 0, 2, 2, 3, 3, 0]


def test_power_and_links_by_hand() -> None:
    m = SignalLinks()  # -40 dBm at 10 cells, exponent 2.5, 3 dB per wall cell, cutoff -70
    free = np.ones((400, 20), dtype=bool)
    free[150:152, :] = False  # a wall two cells thick at x = 150, 151
    a = np.array([[5.5, 10.5]] * 5)
    b = np.array([[10.5, 10.5], [105.5, 10.5], [145.5, 10.5], [155.5, 10.5], [8.5, 10.5]])
    # d = 5 (inside the reference distance), 100, 140, 150 (+ 2 wall cells), 3
    want = [
        -40.0,
        -40.0 - 25.0,
        -40.0 - 25.0 * math.log10(14.0),
        -40.0 - 25.0 * math.log10(15.0) - 6.0,
        -40.0,
    ]
    assert m.power_dbm(free, a, b) == pytest.approx(want)
    assert m.linked(free, a, b).tolist() == [True, True, True, False, True]
    assert m.range_cells == pytest.approx(10.0 * 10.0 ** (30.0 / 25.0))  # 158.49 cells
    # the free-space range is the boundary
    edge = np.array([[5.5, 10.5]]), np.array([[5.5 + 158.4, 10.5]]), np.array([[5.5 + 158.6, 10.5]])
    wide = np.ones((400, 20), dtype=bool)
    assert m.linked(wide, edge[0], edge[1])[0] and not m.linked(wide, edge[0], edge[2])[0]
    # symmetric, and link_pairs agrees pair by pair
    assert m.linked(free, b, a).tolist() == m.linked(free, a, b).tolist()
    pts = np.vstack([a[:1], b[1:4]])
    assert link_pairs(m, free, pts).tolist() == [[0, 1], [0, 2], [1, 2], [1, 3], [2, 3]]


def test_planner_counts_unknown_cells_as_walls() -> None:
    """``C^t`` on the BS's known map: unknown cells attenuate like walls until they are known."""
    occ = np.zeros((100, 12), dtype=bool)  # all free in truth
    known = np.ones_like(occ)
    known[50:53, 4:6] = False  # an unknown hole on the straight line between BS and relay
    bs, relay = np.array([4.5, 4.5]), np.array([94.5, 4.5])
    model = SignalLinks()
    # 90 cells: -40 - 25 log10(9) = -63.86 dBm; the hole is 3 cells on the line: -72.86
    assert model.power_dbm(known & ~occ, bs, relay)[0] == pytest.approx(
        -40.0 - 25.0 * math.log10(9.0) - 9.0
    )
    assert model.linked(~occ, bs, relay)[0]  # in truth they are linked
    builder = GraphBuilder(occ, model, coarse_factor=3, gain_half_width=10)

    def linked(known_now: np.ndarray) -> bool:
        g = builder.build(known_now, bs, relay[None])
        i = int(np.flatnonzero(np.all(np.isclose(g.positions, relay), axis=1))[0])
        return any({0, i} == set(e) for e in g.edges.tolist())

    assert not linked(known)
    assert linked(np.ones_like(occ))  # the hole is known free now: linked (not cached as blocked)


def test_known_walls_block_forever() -> None:
    occ = np.zeros((100, 12), dtype=bool)
    occ[50:55, :] = True  # five wall cells: -63.86 - 15 dB
    model = SignalLinks()
    a, b = np.array([[4.5, 4.5]]), np.array([[94.5, 4.5]])
    assert model.blocked_forever(occ, a, b)[0]
    assert not model.blocked_forever(np.zeros_like(occ), a, b)[0]


def test_scenario_converts_metres_to_cells(tmp_path) -> None:
    from tether.config import load_scenario
    from tether.runner import run

    sc = load_scenario("recurrent_demo")
    sc.sim.max_steps = 15
    sc.team.n_robots = 3
    sc.output.figures = False
    sc.strategy.params.update(
        link_model="signal", signal={"ref_distance_m": 2.0, "wall_loss_db": 4.0}, check=True
    )
    out = run(sc, out_dir=tmp_path / "r")
    assert out.summary["constraint_violations"] == 0
    assert out.summary["final_explored_fraction"] > 0
    from tether.recurrent.strategy import RecurrentParams, _config

    params = RecurrentParams.model_validate(sc.strategy.params)
    cfg = _config(params, sc, 0.1)
    assert cfg.link_model == "signal"
    want = {"ref_power_dbm": -40.0, "ref_distance_cells": 20.0, "exponent": 2.5,
            "wall_loss_db": 4.0, "cutoff_dbm": -70.0}  # fmt: skip
    assert cfg.link_params == want
