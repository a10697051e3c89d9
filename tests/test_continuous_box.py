"""The world's box (floor, ceiling, outer walls) is rigid for strategy `connectivity`."""

from __future__ import annotations

import numpy as np
import pyarrow.parquet as pq

from tether.config import load_scenario, scenario_from_dict
from tether.continuous.connectivity.robot import stay_inside
from tether.runner import run

BOX = np.array([[0.0, 0.0, 0.0], [10.0, 10.0, 3.0]])


def test_stay_inside_clips_and_stops_only_the_wall_component():
    q_old = np.array([[5.0, 5.0, 1.0], [5.0, 5.0, -1.0]])  # the second starts below the floor
    q_new = np.array([[5.5, 4.0, 0.1], [5.0, 5.0, -2.0]])
    v_new = np.array([[0.5, -1.0, -0.9], [0.0, 0.0, -1.0]])
    q, v = stay_inside(q_old, q_new, v_new, BOX, margin_m=0.25)
    np.testing.assert_allclose(q[0], [5.5, 4.0, 0.25])  # stopped at the floor + margin
    np.testing.assert_allclose(v[0], [0.5, -1.0, 0.0])  # sliding along it
    np.testing.assert_allclose(q[1], [5.0, 5.0, -1.0])  # never further out, never pushed in
    inside = np.array([[1.0, 2.0, 2.0]])
    q, v = stay_inside(inside, inside + 0.1, np.ones((1, 3)), BOX, 0.25)
    np.testing.assert_allclose(q, inside + 0.1)  # free motion is untouched
    np.testing.assert_allclose(v, 1.0)


def test_team_pushed_into_the_floor_stays_above_it_and_connected(tmp_path):
    """A constant downward and sideways pull (through the YAML path) meets floor and wall."""
    data = load_scenario("connectivity_empty").model_dump(mode="json")
    data["sim"]["max_steps"] = 120
    data["strategy"]["params"]["external"] = {
        "kind": "constant", "forces": [[-2.0, 0.0, -4.0]], "magnitude_n": 4.5,
    }  # fmt: skip
    outcome = run(scenario_from_dict(data, "floor.yaml"), out_dir=tmp_path, figures=False)
    robots = pq.read_table(tmp_path / "robots.parquet").to_pydict()
    z, x, step = (np.asarray(robots[k]) for k in ("z_m", "x_m", "step"))
    margin = 0.75  # Ro of the outdoor preset
    assert z.min() >= margin - 1e-9 and x.min() >= margin - 1e-9
    last = step == step.max()
    assert np.allclose(z[last], margin, atol=0.05)  # resting on the floor
    assert outcome.summary["connected_all_steps"]
    assert outcome.summary["min_lambda2_weighted"] > 0
    assert outcome.summary["collisions"] == 0
