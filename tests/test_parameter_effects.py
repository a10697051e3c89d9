"""Every scenario parameter changes a run the way its documentation says.

The list of parameters is generated from the models (``_parameters.py``): a parameter
without an effect test or a declared reason fails
:func:`test_every_parameter_has_an_effect_test`. This module holds the scenario's own
blocks (top level, ``world``, ``team``, ``sensing``, ``sim``, ``output``, ``sweep``);
the strategies' parameters are in ``test_parameter_effects_*.py``.
"""

from __future__ import annotations

import importlib
import json
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

from _parameter_runs import SILENT, built, changed, ran
from _parameters import EFFECTS, NO_EFFECT, effect, scenario_parameters
from tether.config import scenario_from_dict, sweep_spec
from tether.runner import build_world, run
from tether.sensing import sense

#: every module of effect tests (a new ``test_parameter_effects_*.py`` is found by its name)
EFFECT_MODULES = sorted(p.stem for p in Path(__file__).parent.glob("test_parameter_effects*.py"))


def test_every_parameter_has_an_effect_test() -> None:
    assert "test_parameter_effects_silent" in EFFECT_MODULES  # the glob found the modules
    for name in EFFECT_MODULES:
        importlib.import_module(name)
    keys = set(scenario_parameters())
    covered = set(EFFECTS) | set(NO_EFFECT)
    assert not keys - covered, f"parameters without an effect test: {sorted(keys - covered)}"
    assert not set(EFFECTS) - keys, f"effect tests of no parameter: {set(EFFECTS) - keys}"
    assert not set(NO_EFFECT) & set(EFFECTS), "a parameter both with and without an effect"
    assert len(keys) > 150  # the walk found the strategies' parameters too


def pairwise_min(q: np.ndarray) -> float:
    d = np.linalg.norm(q[:, None] - q[None], axis=-1)
    return float(d[np.triu_indices(len(q), 1)].min())


# -- top level -------------------------------------------------------------------------


@effect("name", "output.dir")
def test_name_and_output_dir_place_the_run_folder(tmp_path: Path) -> None:
    out = tmp_path / "elsewhere"
    outcome = run(changed(SILENT, name="fleet-a", output__dir=str(out), sim__max_steps=2))
    assert outcome.path.parent == out
    assert outcome.path.name.startswith("fleet-a-s1-")
    assert outcome.summary["scenario"] == "fleet-a"


@effect("seed")
def test_seed_draws_the_team(tmp_path: Path) -> None:
    base = changed(SILENT, team__init={"kind": "random_connected", "spacing_m": 6.0})
    a, b, a2 = (built(changed(base, seed=s)).initial.positions for s in (1, 2, 1))
    np.testing.assert_array_equal(a, a2)
    assert not np.allclose(a, b)


# -- world -------------------------------------------------------------------------------


@effect("world.scene", "world.params")
def test_scene_and_its_params_make_the_world() -> None:
    free = build_world(scenario_from_dict(SILENT), np.random.default_rng(0))
    office = changed(
        SILENT, world={"scene": "office", "dim": 2, "params": {"size_m": [12, 16], "dim": 2}}
    )
    small = build_world(scenario_from_dict(office), np.random.default_rng(0))
    office["world"]["params"]["size_m"] = [20, 30]
    large = build_world(scenario_from_dict(office), np.random.default_rng(0))
    assert not free.has_obstacles and small.has_obstacles
    np.testing.assert_allclose(small.bounds_m[1] - small.bounds_m[0], [12, 16], atol=0.5)
    np.testing.assert_allclose(large.bounds_m[1] - large.bounds_m[0], [20, 30], atol=0.5)


@effect("world.dim")
def test_dim_three_gives_three_coordinates() -> None:
    data = changed(SILENT, world__dim=3)
    data["strategy"]["params"]["trajectory"]["waypoints"] = [[0, 0, 0], [60, 0, 0]]
    r = ran(data, max_steps=3)
    assert r.positions.shape[-1] == 3 and SILENT["world"].get("dim") == 2
    assert r.positions[-1, :, 2].std() > 0  # the grid is a 3-D lattice


# -- team --------------------------------------------------------------------------------


@effect("team.n_robots")
def test_n_robots_is_the_team_size() -> None:
    assert len(built(changed(SILENT, team__n_robots=9)).initial.positions) == 9


@effect("team.init.kind", "team.init.spacing_m")
def test_grid_places_a_lattice_of_the_spacing() -> None:
    for spacing in (4.0, 7.0):
        q = built(changed(SILENT, team__n_robots=9, team__init__spacing_m=spacing)).initial
        assert pairwise_min(q.positions) == pytest.approx(spacing)
        assert len(np.unique(q.positions[:, 0])) == 3  # 3 x 3
    rnd = changed(SILENT, team__init={"kind": "random_connected", "spacing_m": 4.0})
    assert len(np.unique(built(rnd).initial.positions[:, 0])) == 6  # not a lattice


@effect("team.init.min_separation_m")
def test_min_separation_keeps_robots_apart() -> None:
    for sep in (1.0, 3.5):
        init = {"kind": "random_connected", "spacing_m": 5.0, "min_separation_m": sep}
        q = built(changed(SILENT, team__n_robots=12, team__init=init)).initial.positions
        assert pairwise_min(q) >= sep
    loose = {"kind": "random_connected", "spacing_m": 5.0, "min_separation_m": 0.0}
    q = built(changed(SILENT, team__n_robots=12, team__init=loose)).initial.positions
    assert pairwise_min(q) < 3.5


@effect("team.init.center")
def test_center_moves_the_team() -> None:
    a = built(SILENT).initial.positions
    b = built(changed(SILENT, team__init__center=[100.0, -50.0])).initial.positions
    np.testing.assert_allclose(b.mean(0) - a.mean(0), [100.0, -50.0] - a.mean(0), atol=1e-9)


@effect("team.init.extent_m")
def test_uniform_stays_in_its_box() -> None:
    for extent in ([6.0, 6.0], [12.0, 3.0]):
        init = {"kind": "uniform", "extent_m": extent, "center": [0, 0], "min_separation_m": 0.5}
        q = built(changed(SILENT, team__init=init)).initial.positions
        assert (np.abs(q) <= np.array(extent) / 2 + 1e-9).all()
        assert (np.ptp(q, axis=0) > np.array(extent) / 4).all()


@effect("team.init.positions")
def test_positions_are_the_start() -> None:
    pts = [[0.0, 0.0], [5.0, 1.0], [9.0, -2.0]]
    q = built(changed(SILENT, team__n_robots=3, team__init={"kind": "positions", "positions": pts}))
    np.testing.assert_array_equal(q.initial.positions, pts)


# -- sensing -----------------------------------------------------------------------------


def sensed(data: dict, positions: list, seed: int = 0):  # noqa: ANN201
    b = built(data)
    return sense(np.asarray(positions, float), b.sensor, np.random.default_rng(seed), b.world)


LINE = [[0.0, 0.0], [5.0, 0.0], [10.0, 0.0], [0.0, 9.0]]  # 0-2 passes through robot 1


@effect("sensing.range_m")
def test_range_sets_who_senses_whom() -> None:
    assert len(sensed(changed(SILENT, sensing__range_m=6.0), LINE).pairs) == 2
    assert len(sensed(changed(SILENT, sensing__range_m=11.0), LINE).pairs) == 5


@effect("sensing.body_radius_m", "sensing.occlusion")
def test_bodies_hide_robots_behind_them() -> None:
    far = changed(SILENT, sensing__range_m=11.0)
    pairs = {
        (r, occ): {tuple(p) for p in sensed(
            changed(far, sensing__body_radius_m=r, sensing__occlusion=occ), LINE).pairs.tolist()}
        for r in (0.0, 0.5) for occ in (True, False)
    }  # fmt: skip
    assert (0, 2) not in pairs[(0.5, True)]
    assert (0, 2) in pairs[(0.0, True)] and (0, 2) in pairs[(0.5, False)]


def errors(noise: str, radial: float, angular: float) -> tuple[np.ndarray, np.ndarray]:
    data = changed(SILENT, sensing={"range_m": 30.0, "radial_error_m": radial,
                                    "angular_error_deg": angular, "noise": noise})  # fmt: skip
    rng = np.random.default_rng(3)
    obs = sensed(data, rng.uniform(-10, 10, (12, 2)).tolist())
    d_true = np.linalg.norm(obs.true_relative, axis=1)
    d_meas = np.linalg.norm(obs.measured, axis=1)
    cos = np.sum(obs.true_relative * obs.measured, axis=1) / (d_true * d_meas)
    return np.abs(d_meas - d_true), np.degrees(np.arccos(np.clip(cos, -1, 1)))


@effect("sensing.radial_error_m", "sensing.angular_error_deg", "sensing.noise")
def test_noise_is_bounded_by_the_errors_and_its_kind() -> None:
    radial, angle = errors("uniform", 0.5, 10.0)
    assert radial.max() <= 0.5 + 1e-9 and radial.max() > 0.25
    assert angle.max() <= 10.0 + 1e-6 and angle.max() > 5.0
    radial, angle = errors("uniform", 0.1, 2.0)
    assert radial.max() <= 0.1 + 1e-9 and angle.max() <= 2.0 + 1e-6
    radial, angle = errors("bound", 0.5, 10.0)
    np.testing.assert_allclose(radial, 0.5, atol=1e-9)
    np.testing.assert_allclose(angle, 10.0, atol=1e-6)
    radial, angle = errors("none", 0.5, 10.0)
    assert radial.max() < 1e-12 and angle.max() < 1e-4  # arccos near 1: 1e-6 deg of rounding


# -- sim -----------------------------------------------------------------------------------


@effect("sim.dt_s")
def test_dt_is_the_clock_and_scales_the_leaders_step() -> None:
    start = {"kind": "positions", "positions": [[0, 0], [6, 0], [0, 6], [6, 6], [-6, 0], [-6, 6]]}
    travel = {}
    for dt in (0.5, 2.0):
        r = ran(changed(SILENT, sim__dt_s=dt, team__init=start), max_steps=4)
        t = [rec.t_s for rec in r.result.records]
        np.testing.assert_allclose(np.diff(t), dt)
        travel[dt] = r.metrics["leader_travel_m"]
    assert travel[0.5] == pytest.approx(4 * 0.5, rel=0.05)  # 1 m/s for 4 steps of 0.5 s
    assert 3 * travel[0.5] < travel[2.0] <= 4 * 2.0 + 1e-9  # the followers slow it a little


@effect("sim.max_steps")
def test_max_steps_bounds_the_run(tmp_path: Path) -> None:
    for steps in (3, 7):
        outcome = run(changed(SILENT, sim__max_steps=steps), out_dir=tmp_path / str(steps))
        assert outcome.summary["steps"] == steps
        assert pq.read_table(outcome.path / "steps.parquet").num_rows == steps + 1


@effect("sim.collision_distance_m")
def test_collision_distance_counts_close_pairs(tmp_path: Path) -> None:
    pts = {"kind": "positions", "positions": [[0, 0], [1.0, 0], [6, 0]]}
    base = changed(SILENT, team__n_robots=3, team__init=pts, sim__max_steps=1)
    near = ran(changed(base, sim__collision_distance_m=0.5)).result.records[0]
    far = ran(changed(base, sim__collision_distance_m=1.5)).result.records[0]
    assert (near.collisions, far.collisions) == (0, 1)
    for distance, at_start in ((0.5, 0), (1.5, 1)):  # through `tether run`'s path
        out = run(
            changed(base, sim__collision_distance_m=distance), out_dir=tmp_path / str(distance)
        )
        assert pq.read_table(out.path / "steps.parquet")["collisions"][0].as_py() == at_start


# -- strategy ------------------------------------------------------------------------------


@effect("strategy.name")
def test_strategy_name_picks_the_strategy(tmp_path: Path) -> None:
    outcome = run(changed(SILENT, sim__max_steps=2), out_dir=tmp_path / "r")
    assert outcome.summary["strategy"] == "silent"
    assert type(built(SILENT).strategy).name == "silent"
    with pytest.raises(Exception, match="unknown strategy"):
        built(changed(SILENT, strategy__name="silentt"))


# -- output --------------------------------------------------------------------------------


@effect("output.record_every", "output.figures")
def test_record_every_thins_the_tables_and_figures_can_be_skipped(tmp_path: Path) -> None:
    a = run(changed(SILENT, output__record_every=3, output__figures=True), out_dir=tmp_path / "a")
    b = run(changed(SILENT, output__record_every=1), out_dir=tmp_path / "b")
    steps_a = sorted(set(pq.read_table(a.path / "robots.parquet")["step"].to_pylist()))
    steps_b = sorted(set(pq.read_table(b.path / "robots.parquet")["step"].to_pylist()))
    assert steps_a == [0, 3, 6, 9] and steps_b == list(range(11))
    assert (a.path / "figures" / "links.png").is_file()
    assert not (b.path / "figures").exists()
    assert json.loads((a.path / "summary.json").read_text())["steps"] == 10


# -- sweep ---------------------------------------------------------------------------------


@effect("sweep")
def test_sweep_axes_make_the_combinations() -> None:
    data = changed(SILENT, sweep={"strategy.params.d0_m": [5.0, 8.0], "sim.dt_s": [1.0, 2.0]})
    combos = sweep_spec(scenario_from_dict(data)).combinations()
    assert len(combos) == 4
    assert {(c["strategy.params.d0_m"], c["sim.dt_s"]) for c in combos} == {
        (5.0, 1.0), (5.0, 2.0), (8.0, 1.0), (8.0, 2.0)
    }  # fmt: skip
    assert sweep_spec(scenario_from_dict(SILENT)).combinations() == [{}]
