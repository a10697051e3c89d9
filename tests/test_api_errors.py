"""Public functions check their arguments and raise ValueError / TypeError with a clear message."""

from __future__ import annotations

import numpy as np
import pytest

from tether.config import load_scenario
from tether.errors import ScenarioError
from tether.experiments.sweep import run_sweep
from tether.paths.trajectory import Polyline
from tether.runner import Built, build, run
from tether.sensing import SensorModel
from tether.silent import SilentStrategy
from tether.sim import TeamState, simulate
from tether.world import World


def _short_demo() -> dict:
    data = load_scenario("silent_demo").model_dump(mode="json")
    data["sim"]["max_steps"] = 3
    data["output"]["figures"] = False
    return data


@pytest.mark.parametrize(
    ("seed", "error", "match"),
    [
        (-1, ValueError, r"seed must be an integer in \[0, 2\*\*63 - 1\] \(got -1\)"),
        (2**64, ValueError, "seed must be an integer"),
        ("3", TypeError, "seed must be an integer"),
        (1.5, TypeError, "seed must be an integer"),
        (True, TypeError, "seed must be an integer"),
    ],
)
def test_run_and_build_refuse_bad_seeds(tmp_path, seed, error, match):
    with pytest.raises(error, match=match):
        run("silent_demo", out_dir=tmp_path / "r", seed=seed)
    with pytest.raises(error, match=match):
        build("silent_demo", seed=seed)
    assert not (tmp_path / "r").exists()


def test_run_accepts_a_scenario_dict(tmp_path):
    outcome = run(_short_demo(), out_dir=tmp_path / "r", seed=4)
    assert outcome.summary["seed"] == 4 and outcome.summary["steps"] == 3
    bad = _short_demo()
    bad["sensing"]["range_m"] = -1
    with pytest.raises(ScenarioError, match=r"<scenario dict>: sensing.range_m: .*greater than 0"):
        run(bad, out_dir=tmp_path / "bad")


def test_build_accepts_names_paths_and_dicts(tmp_path):
    by_name = build("silent_demo")
    path = load_scenario("silent_demo").base_dir / "silent_demo.yaml"
    by_path = build(path)
    by_dict = build(_short_demo())
    for built in (by_name, by_path, by_dict):
        assert isinstance(built, Built) and built.initial.n == 12
    assert np.array_equal(by_name.initial.positions, by_path.initial.positions)
    with pytest.raises(TypeError, match="scenario must be a Scenario, a dict"):
        build(42)
    with pytest.raises(ScenarioError, match="nowhere.yaml: file not found"):
        build("nowhere.yaml")


def test_run_checks_out_dir_and_figures(tmp_path):
    with pytest.raises(TypeError, match="out_dir must be a path"):
        run(_short_demo(), out_dir=3)
    with pytest.raises(TypeError, match="figures must be True, False or None"):
        run(_short_demo(), out_dir=tmp_path / "r", figures="no")


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"noise": "gaussian"}, ValueError, "noise must be 'none', 'uniform' or 'bound'"),
        ({"range_m": float("nan")}, ValueError, "range_m must be finite"),
        ({"range_m": float("inf")}, ValueError, "range_m must be finite"),
        ({"range_m": -1.0}, ValueError, "range_m must be > 0"),
        ({"range_m": "15"}, TypeError, "range_m must be a number"),
        ({"angular_error_rad": 2.0}, ValueError, "angular_error_rad must be below pi/2"),
        ({"radial_error_m": 20.0}, ValueError, "radial_error_m must be smaller than range_m"),
        ({"occlusion": "yes"}, TypeError, "occlusion must be True or False"),
    ],
)
def test_sensor_model_checks_its_arguments(kwargs, error, match):
    with pytest.raises(error, match=match):
        SensorModel(**{"range_m": 15.0, **kwargs})


@pytest.mark.parametrize(
    "waypoints",
    [np.empty((0, 2)), [], [[0.0, 0.0], [np.nan, 1.0]], [[0.0, np.inf]], [[0, 0], [1]], "ab"],
    ids=["no-points", "empty-list", "nan", "inf", "ragged", "text"],
)
def test_polyline_refuses_empty_and_non_finite_paths(waypoints):
    with pytest.raises(ValueError, match="waypoints must be"):
        Polyline(waypoints)


def test_polyline_of_one_point_is_a_point():
    line = Polyline([[1.0, 2.0]])
    assert line.length_m == 0.0 and np.array_equal(line.at(5.0), [1.0, 2.0])


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"d_max_m": -5}, ValueError, "d_max_m must be a finite number > 0"),
        ({"d_max_m": float("nan")}, ValueError, "d_max_m must be a finite number > 0"),
        ({"gamma": 0}, ValueError, "gamma must be a finite number > 0"),
        ({"d0_m": "8"}, TypeError, "d0_m must be a number"),
        ({"radial_error_m": -0.1}, ValueError, "radial_error_m must be a finite number >= 0"),
        ({"radial_error_m": 20.0}, ValueError, "radial_error_m must be smaller than d_max_m"),
        ({"angular_error_rad": 3.0}, ValueError, "angular_error_rad must be below pi/2"),
        ({"cost": "nearest"}, ValueError, "cost must be 'desired_distance' or 'farthest'"),
        ({"leader": 1.5}, TypeError, "leader must be a robot index"),
        ({"trajectory": "north"}, TypeError, "trajectory must be a Polyline or a function"),
        ({"max_speed_mps": 0.0}, ValueError, "max_speed_mps must be a finite number > 0"),
    ],
)
def test_silent_strategy_checks_its_arguments(kwargs, error, match):
    args = {"d_max_m": 15.0, "trajectory": Polyline([[0, 0], [30, 0]]), **kwargs}
    with pytest.raises(error, match=match):
        SilentStrategy(**args)


def test_simulate_checks_its_arguments():
    strategy = SilentStrategy(d_max_m=15.0, trajectory=Polyline([[0, 0], [30, 0]]))
    start = TeamState.at_rest(np.array([[0.0, 0.0], [5.0, 0.0]]))
    args = (World(dim=2), SensorModel(15.0), strategy, start)
    with pytest.raises(TypeError, match="rng must be a numpy.random.Generator"):
        simulate(*args, dt_s=1.0, max_steps=3, rng=None)
    with pytest.raises(ValueError, match="dt_s must be a positive finite number"):
        simulate(*args, dt_s=float("inf"), max_steps=3, rng=np.random.default_rng(0))
    with pytest.raises(ValueError, match="max_steps must be a non-negative integer"):
        simulate(*args, dt_s=1.0, max_steps=-1, rng=np.random.default_rng(0))
    result = simulate(*args, dt_s=1.0, max_steps=3, rng=np.random.default_rng(0))
    assert result.steps == 3


def test_run_sweep_checks_seeds_and_workers(tmp_path):
    scenario = load_scenario("silent_paper")
    for seeds in (0, -3, 1.5):
        with pytest.raises(ValueError, match="seeds must be a positive integer"):
            run_sweep(scenario, tmp_path / "a", seeds=seeds)
    with pytest.raises(ValueError, match="workers must be a positive integer"):
        run_sweep(scenario, tmp_path / "b", executor="processes", workers=0)
    assert not (tmp_path / "a").exists() and not (tmp_path / "b").exists()
