"""Table 2 of the continuous-connectivity paper (radii, lambda2 thresholds, ``k_V``) in
``connectivity`` and ``multi_target``: each parameter changes the weights of App. A or the
barrier the way ``docs/continuous.md`` says, set from a scenario and read back from the
strategy that ``build`` made (weights of probe configurations), or from short runs."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest

from _continuous_runs import STRATEGIES, both, moved_m, pulled, reset, run, scenario
from _parameters import effect
from tether.continuous.connectivity.params import TABLE2, TRAVEL_TABLE2
from tether.continuous.exploration.params import PRESET_DEFAULTS

BOTH = pytest.mark.parametrize("strategy", STRATEGIES)
RADII = ("rs_inner_m", "rs_m", "ro_m", "ro_outer_m", "rc_m", "rc_outer_m")


def probe(strategy: str, xy: list[list[float]], data: dict | None = None, **params: Any):
    """``W_ij`` of the pairs of the 4-robot configuration ``xy`` (2-D; MT's at z = 5 m),
    from the strategy built with ``params``: ``{(i, j): W_ij}`` of the pairs with W > 0."""
    data = data or scenario(strategy, **params)
    q = np.asarray(xy, dtype=float)
    if data["world"]["dim"] == 3:
        q = np.column_stack([q, np.full(len(q), 5.0)])
    s = reset(data)
    pairs, w = s.evaluate(q)[1][0].active()
    return {tuple(p): float(x) for p, x in zip(pairs.tolist(), w, strict=True)}


def far_apart(*pair: list[float]) -> list[list[float]]:
    """Two probe robots (0 and 1) and two more far from everything."""
    return [*pair, [60.0, 60.0], [-60.0, 60.0]]


# -- the preset ----------------------------------------------------------------------------


@BOTH
@effect(*both("preset"))
def test_the_preset_sets_table_2_and_explicit_values_override_it(strategy: str) -> None:
    for preset in ("outdoor", "office", "experiment"):
        s = reset(tight(scenario(strategy, preset=preset, lambda2_null=2.0)))
        for key in RADII + ("lambda2_min", "lambda2_null"):
            want = 2.0 if key == "lambda2_null" else TABLE2[preset][key]
            assert getattr(s.conn, key) == want, (preset, key)
        if strategy == "multi_target":
            travel, ours = TRAVEL_TABLE2[preset], PRESET_DEFAULTS[preset]
            assert s.planner.r_grid_m == travel["r_grid_m"] and s.planner.rz_m == travel["rz_m"]
            for key in ("sigma", "v_cruise_mps", "xc_frac", "xm_frac"):
                assert getattr(s.params, key) == travel[key], (preset, key)
            assert s.consensus.gain_per_s == ours.get("k_lambda_per_s", 5.0)
            assert s.planner.replan_stalled_s == ours.get("replan_stalled_s")
            assert s.params.help_lambda_factor == ours.get("help_lambda_factor")
    # what the radii do: robots 2.4 m apart are linked outdoors (Rs = 6 m) and in the
    # office (Rs = 2.5 m), 2.6 m apart only outdoors
    for preset, linked in (("outdoor", True), ("office", False)):
        data = tight(scenario(strategy, preset=preset))
        assert (0, 1) in probe(strategy, far_apart([0, 0], [2.4, 0]), data)
        assert ((0, 1) in probe(strategy, far_apart([0, 0], [2.6, 0]), data)) == linked


def tight(data: dict[str, Any]) -> dict[str, Any]:
    """The row 1.5 m apart: in the safe set of every preset."""
    for k, p in enumerate(data["team"]["init"]["positions"]):
        p[0] = 1.5 * k
    return data


# -- the radii -------------------------------------------------------------------------------


@BOTH
@effect(*both("rs_m"))
def test_rs_is_the_range_of_a_link(strategy: str) -> None:
    at_5m = far_apart([0, 0], [5, 0])
    assert (0, 1) in probe(strategy, at_5m)  # Rs = 6 m
    assert (0, 1) not in probe(strategy, at_5m, rs_m=4.8)
    w6, w8 = probe(strategy, at_5m)[(0, 1)], probe(strategy, at_5m, rs_m=8.0)[(0, 1)]
    assert 0 < w6 < w8 < 1  # a longer range: a stronger link at the same distance


@BOTH
@effect(*both("rs_inner_m"))
def test_rs_inner_is_where_a_link_starts_to_weaken(strategy: str) -> None:
    at_3m = far_apart([0, 0], [3, 0])
    assert probe(strategy, at_3m, rs_inner_m=3.5)[(0, 1)] == 1.0
    assert 0 < probe(strategy, at_3m)[(0, 1)] < 1.0  # R's = 2.5 m


@BOTH
@effect(*both("rc_m", "rc_outer_m"))
def test_the_collision_band_weakens_and_cuts_close_pairs(strategy: str) -> None:
    at_2m = far_apart([0, 0], [2, 0])
    assert 0 < probe(strategy, at_2m)[(0, 1)] < 1  # (Rc, R'c) = (1, 2.5): in the band
    assert probe(strategy, at_2m, rc_outer_m=1.9)[(0, 1)] == 1.0  # beyond R'c
    assert (0, 1) not in probe(strategy, at_2m, rc_m=2.1, rc_outer_m=2.4)  # within Rc


@pytest.mark.parametrize("rc_m", [1.0, 2.0])
@effect("connectivity:rc_m")
def test_robots_pushed_together_stay_farther_than_rc(rc_m: float) -> None:
    push = {"kind": "constant", "forces": [[0, 0], [3, 0], [-3, 0], [0, 0]], "magnitude_n": 3}
    r = run(scenario("connectivity", external=push, rc_m=rc_m, rc_outer_m=2.4), 100)
    closest = r.metrics["min_robot_distance_m"]
    assert rc_m < closest < (2.0 if rc_m == 1.0 else 2.4)  # pushed into the band, not through


def wall_world(tmp_path: Path) -> dict[str, Any]:
    """A 20 m x 20 m box with a wall along x = 10 m from y = 0 to 14 m."""
    path = tmp_path / "wall.csv"
    np.savetxt(path, [[10.0, y] for y in np.arange(0.0, 14.01, 0.2)], delimiter=",")
    return {
        "scene": "user_points",
        "dim": 2,
        "params": {"path": str(path), "bounds_m": [[0, 0], [20, 20]], "resolution_m": 0.25},
    }


def in_the_wall_world(strategy: str, tmp_path: Path, **params: Any) -> dict[str, Any]:
    data = scenario(strategy, **params)
    data["world"] = wall_world(tmp_path)
    data["team"]["init"]["positions"] = [[6, 2], [6, 5], [6, 8], [6, 11]]
    if strategy == "multi_target":
        data["strategy"]["params"]["targets"]["params"]["queues"][0]["targets"] = [[3.0, 11.0]]
    return data


@BOTH
@effect(*both("ro_m", "ro_outer_m"))
def test_the_obstacle_band_weakens_and_cuts_lines_of_sight(strategy: str, tmp_path) -> None:
    """Pair (0, 1) sees past the wall's end 1.2 m away; pair (2, 3) is as long, in the open:
    the ratio of their weights is the obstacle factor B of the line of sight."""
    xy = [[8.0, 15.2], [12.0, 15.2], [1.0, 19.0], [5.0, 19.0]]

    def factor(**radii: float) -> float:
        w = probe(strategy, xy, in_the_wall_world(strategy, tmp_path, **radii))
        return w.get((0, 1), 0.0) / w[(2, 3)]

    assert 0 < factor() < 1  # (Ro, R'o) = (0.75, 1.75)
    assert factor(ro_m=0.5, ro_outer_m=1.1) == 1.0
    assert factor(ro_m=1.3) == 0.0


@pytest.mark.parametrize("ro_m", [0.75, 1.5])
@effect("connectivity:ro_m")
def test_a_team_pushed_at_a_wall_stays_farther_than_ro(ro_m: float, tmp_path) -> None:
    push = {"kind": "constant", "forces": [[2.0, 0.0]], "magnitude_n": 2.0}
    data = in_the_wall_world("connectivity", tmp_path, external=push, ro_m=ro_m, ro_outer_m=2.0)
    clearance = run(data, 100).metrics["min_obstacle_clearance_m"]
    assert ro_m < clearance < (1.5 if ro_m == 0.75 else 2.0)


# -- the barrier -----------------------------------------------------------------------------


@BOTH
@effect(*both("lambda2_min"))
def test_the_barrier_holds_lambda2_above_lambda2_min(strategy: str) -> None:
    low = run(pulled(strategy), 80).metrics
    high = run(pulled(strategy, lambda2_min=0.2), 80).metrics
    assert low["min_lambda2_weighted"] < 0.2 < high["min_lambda2_weighted"]
    assert low["safe_set_exits"] == high["safe_set_exits"] == 0


@BOTH
@effect(*both("lambda2_null"))
def test_above_lambda2_null_the_connectivity_force_is_zero(strategy: str) -> None:
    """The row's lambda2 is about 0.25; nothing else pushes in the first 3 periods (MT's
    prime is not elected yet): with lambda2_null below it nobody moves at all."""
    assert moved_m(run(scenario(strategy), 3)).max() > 1e-4  # lambda2_null = 1
    assert moved_m(run(scenario(strategy, lambda2_null=0.2), 3)).max() == 0.0
    low = run(pulled(strategy, lambda2_null=0.2), 80).metrics["min_lambda2_weighted"]
    assert low < 0.5 * run(pulled(strategy), 80).metrics["min_lambda2_weighted"]


@BOTH
@effect(*both("potential_gain_n"))
def test_a_larger_potential_gain_keeps_lambda2_higher_under_the_same_pull(strategy: str) -> None:
    soft = run(pulled(strategy), 80).metrics["min_lambda2_weighted"]
    stiff = run(pulled(strategy, potential_gain_n=4.0), 80).metrics["min_lambda2_weighted"]
    assert stiff > 1.5 * soft > 0
