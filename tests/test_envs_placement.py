"""The compiled start of the vector form against ``tether run``'s placement, seed by seed.

The reference is :func:`tether.runner.place_team` with ``np.random.default_rng(seed)``
(numpy's generator, scipy's k-d trees, the grid's line of sight): what ``tether run
--seed`` places. The compiled placement (:mod:`tether.envs.vector_placement`, its random
stream :mod:`tether.envs.vector_random`) must give the same positions to the last bit,
and refuse exactly the seeds ``tether run`` refuses.
"""

from __future__ import annotations

import numpy as np
import pytest
from numba import njit
from scipy.spatial import cKDTree

import tether.envs as te
from tether import jit
from tether.config import InitConfig, load_scenario
from tether.envs import vector_placement, vector_random
from tether.envs.vector_start import compiled_plan, place
from tether.errors import ScenarioError
from tether.runner import as_scenario, build, make_sensor, place_team
from tether.scenario_world import build_world
from tether.team import _first_come

pytestmark = pytest.mark.timeout(900)  # the first call compiles the kernels (cold cache)

#: seeds of every case: small ones, and ones of two 32-bit words (SeedSequence's entropy)
SEEDS = [*range(40), 2**32, 2**32 + 7, 2**40 + 3, 2**63 - 1]


@njit(cache=True)
def _draws(seed, kinds, highs):  # noqa: ANN001, ANN202
    st = np.zeros(vector_random.STATE_WORDS, np.uint64)
    vector_random.seed_state(seed, st)
    out = np.empty(len(kinds))
    for i in range(len(kinds)):
        if kinds[i] == 0:
            out[i] = vector_random.bounded(st, highs[i])
        elif kinds[i] == 1:
            out[i] = vector_random.standard_normal(st)
        else:
            out[i] = vector_random.next_double(st)
    return out


def test_the_compiled_stream_is_numpys() -> None:
    pick = np.random.default_rng(5)
    for seed in SEEDS:
        kinds = pick.integers(0, 3, 300)
        highs = pick.integers(0, 40, 300)
        highs[::17] = 2**31 + 5  # Lemire's rejection is taken now and then
        g = np.random.default_rng(seed)
        draw = {
            0: lambda h, g=g: g.integers(h + 1, size=1)[0],
            1: lambda h, g=g: g.normal(size=1)[0],
            2: lambda h, g=g: g.random(),
        }
        want = [draw[k](h) for k, h in zip(kinds, highs, strict=True)]
        np.testing.assert_array_equal(_draws(seed, kinds, highs), np.array(want, float))
    ones = np.ones(200_000, np.int64)  # the ziggurat's wedges and tail (|x| > 3.65) too
    for seed in (0, 2**33):
        want = np.random.default_rng(seed).standard_normal(len(ones))
        assert np.abs(want).max() > 3.7
        np.testing.assert_array_equal(_draws(seed, ones, ones), want)


OFFICE_2D = {
    "scene": "office",
    "dim": 2,
    "params": {"size_m": [16.0, 30.0], "resolution_m": 0.1, "dim": 2},
}


def _scenario(n: int, init: dict, world: dict | None = None, range_m: float = 15.0) -> dict:
    data = load_scenario("silent_demo").model_dump(mode="json")
    data["team"]["n_robots"], data["team"]["init"] = n, init
    data["sensing"]["range_m"] = range_m
    if world is not None:  # the office's corridor runs along y at x = 8 m
        data["world"] = world
        data["strategy"]["params"]["trajectory"]["waypoints"] = [[8.0, 15.0], [8.0, 28.0]]
    return data


def _random(spacing: float, sep: float, center: list | None = None) -> dict:
    return {"kind": "random_connected", "spacing_m": spacing, "min_separation_m": sep,
            "center": center}  # fmt: skip


CASES = {
    "3 robots, free plane": _scenario(3, _random(8.0, 2.0, [0.0, 0.0])),
    "35 robots, free plane": _scenario(35, _random(8.0, 2.0, [0.0, 0.0])),
    "90 robots: batches of several, first come": _scenario(90, _random(4.0, 2.0, [0.0, 0.0])),
    "no separation": _scenario(12, _random(5.0, 0.0, [0.0, 0.0])),
    "office walls": _scenario(12, _random(3.0, 0.5, [8.0, 15.0]), OFFICE_2D, 5.0),
    "walls, some seeds refused (range < spacing)": _scenario(
        8, _random(3.0, 0.5, [8.0, 15.0]), OFFICE_2D, 2.5
    ),
    "uniform box": _scenario(
        12, {"kind": "uniform", "extent_m": [25.0, 25.0], "min_separation_m": 2.5}
    ),
}


def _office_3d() -> tuple:
    """The 3-D office of ``multi_target_office`` with a random connected team of 10."""
    scenario = load_scenario("multi_target_office")
    world = build_world(scenario, np.random.default_rng(0))
    free = np.argwhere(world.grid.free_mask())
    center = world.grid.to_world(free[len(free) // 2])[0]
    init = InitConfig(kind="random_connected", spacing_m=2.0, min_separation_m=0.6,
                      center=center.tolist())  # fmt: skip
    team = scenario.team.model_copy(update={"n_robots": 10, "init": init})
    return scenario.model_copy(update={"team": team}), world


def _compare(scenario: object, world: object, seeds: list[int]) -> int:
    """Assert the compiled teams of ``seeds`` are ``place_team``'s; returns the refusals."""
    sensor = make_sensor(scenario)
    n = scenario.team.n_robots
    plan = compiled_plan(scenario.team.init, n, world, sensor.range_m)
    with jit.using(True):  # the tests pin TETHER_JIT=0 (tests/conftest.py)
        got, ok = place(plan, np.array(seeds), n, world.dim)
    refused = 0
    for k, seed in enumerate(seeds):
        try:
            want = place_team(scenario, world, sensor, np.random.default_rng(seed))
        except ScenarioError:
            assert not ok[k], f"seed {seed}: placed, but tether run refuses it"
            refused += 1
            continue
        assert ok[k], f"seed {seed}: refused, but tether run places it"
        np.testing.assert_array_equal(got[k], want, err_msg=f"seed {seed}")
    return refused


@pytest.mark.parametrize("case", list(CASES))
def test_compiled_placement_is_tether_runs(case: str) -> None:
    scenario = as_scenario(CASES[case])
    world = build_world(scenario, np.random.default_rng(scenario.seed))
    refused = _compare(scenario, world, SEEDS)
    assert (refused > 0) == ("refused" in case)


def test_compiled_placement_in_a_3d_office() -> None:
    scenario, world = _office_3d()
    assert world.has_obstacles and world.dim == 3
    assert _compare(scenario, world, SEEDS[:25]) == 0


def test_first_come_is_teams_on_chains_longer_than_its_rounds() -> None:
    """The first-come rule within a batch, in the same rounds: a chain of close candidates
    decides one more per round, so a long chain leaves the rest undecided (not tried)."""
    pick = np.random.default_rng(2)
    undecided = 0
    for trial in range(200):
        k = int(pick.integers(2, 40))
        if trial % 2:  # a chain along x: neighbours closer than the separation
            pts = np.stack([np.cumsum(pick.uniform(0.5, 1.9, k)), pick.uniform(0, 0.2, k)], 1)
        else:
            pts = pick.uniform(0.0, 7.0, (k, 2))
        pairs = cKDTree(pts).query_pairs(2.0, output_type="ndarray")
        if not len(pairs):
            continue
        keep, decided = _first_come(k, pairs)
        state = np.empty(k, np.int64)
        m, got = vector_placement._first_come(pts, np.arange(k), k, 4.0, state)
        assert (m, got) == (len(pairs), decided)
        np.testing.assert_array_equal(state == 1, keep)
        undecided += decided < k
    assert undecided > 10


def test_vector_reset_places_every_copy_as_tether_run(monkeypatch: pytest.MonkeyPatch) -> None:
    data = _scenario(3, _random(8.0, 2.0, [0.0, 0.0]))
    venv = te.vector_env(data, 6)
    with jit.using(True):
        venv.reset(seed=20)
    compiled = venv.positions.copy()
    for e in range(6):
        np.testing.assert_array_equal(compiled[e], build(data, 20 + e).initial.positions)

    def refuse(*args: object) -> None:
        raise AssertionError("the kernel ran with the kernels switched off")

    monkeypatch.setattr(vector_placement, "place_all", refuse)
    with jit.using(False):
        assert not jit.allowed()
        venv.reset(seed=20)  # copy by copy in Python, the same teams
    np.testing.assert_array_equal(venv.positions, compiled)
    with jit.using(True), pytest.raises(AssertionError, match="switched off"):
        assert jit.allowed()
        venv.reset(seed=20)


def test_a_seed_tether_run_refuses_fails_the_reset_with_its_error() -> None:
    data = CASES["walls, some seeds refused (range < spacing)"]
    scenario = as_scenario(data)
    world = build_world(scenario, np.random.default_rng(0))
    sensor = make_sensor(scenario)
    bad = next(s for s in range(100) if not _places(scenario, world, sensor, s))
    good = next(s for s in range(100) if _places(scenario, world, sensor, s))
    data["seed"] = good
    venv = te.vector_env(data, 1)
    with jit.using(True), pytest.raises(ScenarioError, match="the initial team is not connected"):
        venv.reset(seed=bad)


def _places(scenario: object, world: object, sensor: object, seed: int) -> bool:
    try:
        place_team(scenario, world, sensor, np.random.default_rng(seed))
    except ScenarioError:
        return False
    return True


@pytest.mark.parametrize("name", ["connectivity_empty", "multi_target_empty"])
def test_fixed_and_strategy_starts_are_tether_runs(name: str) -> None:
    """``team.init`` positions (placed once) and a strategy's own start (in Python)."""
    venv = te.vector_env(name, 2, map_patch_cells=1)
    with jit.using(True):
        venv.reset(seed=3)
    for e in range(2):
        np.testing.assert_array_equal(venv.positions[e], build(name, 3 + e).initial.positions)
