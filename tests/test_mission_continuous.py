"""The continuous-connectivity paradigm on the mission: linked to the base at every step."""

from __future__ import annotations

import numpy as np
import pytest

from tether.config import apply_overrides, read_scenario_data, scenario_from_dict
from tether.errors import ScenarioError
from tether.graph import components
from tether.mission.continuous_exploration import clear_base
from tether.mission.frontier_targets import FrontierPicker
from tether.record import TrajectoryRecorder
from tether.runner import build
from tether.sensing.links import link_pairs
from tether.sim import simulate
from tether.world.grid import OccupancyGrid

SMALL = ["world.params.size_m=[12.0, 14.0]", "team.n_robots=4"]


def built(*sets: str, name: str = "mission_continuous"):
    data, label, base = read_scenario_data(name)
    data = apply_overrides(data, [*SMALL, *sets], label)
    return build(scenario_from_dict(data, label, base))


@pytest.fixture(scope="module")
def mission_run():
    """One 90 s run of 4 robots on a small office floor, with its records."""
    b = built("sim.max_steps=90")
    rec = TrajectoryRecorder()
    base0 = b.initial.fixed[0].copy()
    simulate(b.world, None, b.strategy, b.initial, dt_s=1.0, max_steps=90, rng=b.rng,
             recorder=rec)  # fmt: skip
    return b, rec, base0


def test_every_robot_is_linked_to_the_base_station_at_every_step(mission_run) -> None:
    b, rec, base0 = mission_run
    run = b.strategy
    linked = np.asarray(run.log.linked)  # (steps + 1, n) by the mission's own link model
    assert linked.shape == (91, 4) and linked.all()
    # an independent check: the links of the recorded positions, the base station a node
    free = ~run.grid.occupied
    for q in rec.positions[::5]:
        cells = np.vstack([run.sim.base[None], (q - run.grid.origin_m) / run.grid.resolution_m])
        count, _ = components(5, link_pairs(run.sim.link, free, cells))
        assert count == 1
    # the controller's promise: lambda2 of the weighted graph with the base station
    # (step 0, then one per step; the controller plans one step ahead of the simulator)
    lam = np.asarray(run.policy.lambda2_series)
    assert len(lam) == 92 and (lam > run.policy.params.lambda2_min).all()
    m = run.metrics()
    assert m["controller_success"] is True and m["safe_set_exits"] == 0
    # the base station is a fixed node: it never moved
    assert np.array_equal(run.policy.state.positions[-1], base0)
    assert np.allclose(run.to_m(run.sim.base), base0)


def test_it_explores_and_writes_the_shared_mission_metrics(mission_run) -> None:
    b, _, _ = mission_run
    m = b.strategy.metrics()
    mission = m["mission"]
    assert mission["linked_to_base_min"] == 1.0 and mission["all_linked_frac"] == 1.0
    assert mission["latency_undelivered_frac"] == 0.0  # linked: everything is delivered
    log = b.strategy.log
    assert log.base_explored[-1] > log.base_explored[0] + 0.1  # it explores
    assert max(mission["path_length_m"]) > 3.0
    assert m["frontiers_given"] >= 4 and m["targets_total"] == m["frontiers_given"]
    # the same keys as every paradigm of the mission
    other = built("sim.max_steps=2", name="mission_unconstrained")
    simulate(other.world, None, other.strategy, other.initial, dt_s=1.0, max_steps=2,
             rng=other.rng)  # fmt: skip
    assert set(other.strategy.metrics()["mission"]) == set(mission)


def test_targets_are_frontiers_of_the_shared_map_when_given(mission_run) -> None:
    b, rec, _ = mission_run
    run = b.strategy
    log, grid = run.log, run.grid
    taken = [e for e in rec.events if e["kind"] == "target_taken"]
    assert len(taken) >= 4
    shape = grid.occupied.shape
    base_step = log.base_step.reshape(shape)
    for e in taken:
        cell = np.floor(grid.to_cell(np.asarray(e["position_m"])[None])[0]).astype(int)
        step = e["step"]
        known = (base_step >= 0) & (base_step <= step)
        assert known[tuple(cell)] and not grid.occupied[tuple(cell)], e  # known free
        lo, hi = np.maximum(cell - 7, 0), cell + 8
        assert not known[lo[0] : hi[0], lo[1] : hi[1]].all(), e  # unknown cells beside it


def test_frontier_picker_takes_the_best_frontier_and_skips_banned_and_taken() -> None:
    occupied = np.zeros((60, 90), dtype=bool)
    known = np.zeros_like(occupied)
    known[:40] = True  # a frontier along x = 40 (the row of cells x = 39): 3 clusters of 30
    picker = FrontierPicker(occupied, coarse_factor=3, gain_half_width=10, spacing_cells=12)
    pos = np.array([[5.0, 15.0], [6.0, 15.0]])
    [first] = picker.choose(known, pos, [0], np.empty((0, 2)))
    assert 36 <= first.cell[0] <= 40 and first.gain > 0
    # a second robot does not take the same frontier (spacing), a banned one is never chosen
    both = picker.choose(known, pos, [0, 1], np.empty((0, 2)))
    assert np.linalg.norm(both[0].cell - both[1].cell) >= 12
    for c in both:
        picker.ban(c.cell)
    [again] = picker.choose(known, pos, [0], np.empty((0, 2)))  # the third cluster
    assert all(np.linalg.norm(a.cell - c.cell) > 3 for a in [again] for c in both)
    known[:] = True  # nothing left to explore: no target
    assert picker.choose(known, pos, [0, 1], np.empty((0, 2))) == []


def test_the_base_station_moves_off_a_wall_to_the_nearest_clear_point() -> None:
    occupied = np.zeros((50, 50), dtype=bool)
    occupied[20, :] = True  # a wall at x = 2 m; the base station beside it, on its left
    grid = OccupancyGrid(occupied, 0.1)
    got = clear_base(grid, np.array([1.85, 2.5]), 0.6)
    assert grid.clearance_m(got[None])[0] > 0.6 and got[0] < 2.0  # same side of the wall
    assert np.linalg.norm(got - [1.85, 2.5]) < 0.6
    far = np.array([0.8, 2.5])
    assert np.array_equal(clear_base(grid, far, 0.6), far)  # clear already: kept


def test_failures_and_bad_controller_parameters_are_one_line_errors() -> None:
    with pytest.raises(ScenarioError, match="strategy.params.failures"):
        built("strategy.params.failures.random=1")
    with pytest.raises(ScenarioError, match="strategy.params.multi_target"):
        built("strategy.params.multi_target.rz_m=-1")
