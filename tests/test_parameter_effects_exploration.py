"""Every parameter of the exploration strategies (``recurrent``, ``utility`` and the
mission's ``unconstrained`` and ``silent_exploration``) changes a run the way its
documentation says, set from a scenario (YAML keys, not the classes)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from _parameter_runs import Ran, changed, ran
from _parameters import NO_EFFECT, effect
from tether.errors import ScenarioError

#: a 12 x 16 m procedural office at 0.1 m per cell, four robots from a corner
EXPLORE = {
    "name": "explore",
    "seed": 0,
    "world": {"scene": "office", "dim": 2,
              "params": {"size_m": [12.0, 16.0], "resolution_m": 0.1, "dim": 2, "seed": 3}},
    "team": {"n_robots": 4},
    "sensing": {"range_m": 3.0},
    "sim": {"dt_s": 1.0, "max_steps": 40},
    "strategy": {"name": "recurrent", "params": {"base_m": [2.0, 2.0], "comm_range_m": 6.0}},
    "output": {"figures": False},
}  # fmt: skip
#: the strategies on the exploration simulator; they share its parameters
EXPLORERS = (
    "recurrent",
    "utility",
    "unconstrained",
    "silent_exploration",
    "continuous_exploration",
)
BOTH = pytest.mark.parametrize("name", EXPLORERS)


def for_strategy(name: str, **changes: object) -> dict:
    """EXPLORE run by strategy ``name`` (silent_exploration: d0 below the link range)."""
    data = changed(EXPLORE, strategy__name=name, **changes)
    if name == "silent_exploration":
        params = data["strategy"]["params"]
        params["d0_m"] = 0.6 * float(params.get("comm_range_m", 6.0))
    return data


def explore(name: str, steps: int | None = None, **params: object) -> Ran:
    data = for_strategy(name)
    data["strategy"]["params"].update(params)
    if name == "silent_exploration" and "d0_m" not in params:
        data["strategy"]["params"]["d0_m"] = 0.6 * float(data["strategy"]["params"]["comm_range_m"])
    return ran(data, max_steps=steps)


def explored(r: Ran) -> np.ndarray:
    return np.asarray(r.recorder.step_columns()["explored_fraction"])


def travel(r: Ran) -> np.ndarray:
    """Each robot's path length (metres) over the recorded steps."""
    return np.linalg.norm(np.diff(r.positions, axis=0), axis=2).sum(axis=0)


def shared(*keys: str) -> list[str]:
    return [f"{s}:{k}" for s in EXPLORERS for k in keys]


@BOTH
@effect(*shared("speed_m_s"))
def test_speed_bounds_each_step_and_speeds_the_team(name: str) -> None:
    slow, fast = explore(name, speed_m_s=0.2), explore(name, speed_m_s=0.6)
    # the continuous controller cruises below its top speed (cruise_fraction), as the
    # paper's traveling force does; the others move at the speed bound
    reach = 0.3 if name == "continuous_exploration" else 0.9
    for r, speed in ((slow, 0.2), (fast, 0.6)):
        step = np.linalg.norm(np.diff(r.positions, axis=0), axis=2)
        assert step.max() <= speed + 1e-9 and step.max() > reach * speed
    assert travel(fast).sum() > 1.5 * travel(slow).sum()


@BOTH
@effect(*shared("fov_deg", "sensor_resolution_deg"))
def test_a_wider_or_finer_scan_sees_more(name: str) -> None:
    def seen(r: Ran) -> int:  # cells some robot knows
        return int(np.any(r.built.strategy.sim.knowledge.local_known, axis=0).sum())

    assert seen(explore(name, 5, fov_deg=180.0)) > seen(explore(name, 5, fov_deg=20.0))
    coarse, fine = explore(name, 1, sensor_resolution_deg=15.0), explore(name, 1)
    assert explored(fine)[0] > 1.2 * explored(coarse)[0]  # the first, full-circle scan


SCANNERS = [s for s in EXPLORERS if s not in ("silent_exploration", "continuous_exploration")]


@pytest.mark.parametrize("name", SCANNERS)
@effect(*[f"{s}:scan_steps" for s in SCANNERS])
def test_slower_scans_hold_the_robots(name: str) -> None:
    def standing(r: Ran) -> int:  # robot-steps without a move
        return int((np.linalg.norm(np.diff(r.positions, axis=0), axis=2)[1:] == 0).sum())

    assert standing(explore(name, scan_steps=8)) > standing(explore(name)) + 10


def test_silent_exploration_refuses_scans() -> None:
    """Its robots move by the steering law and never stop at a frontier goal to scan."""
    with pytest.raises(ScenarioError, match="scan_steps"):
        explore("silent_exploration", 1, scan_steps=8)


@pytest.mark.parametrize("name", [s for s in EXPLORERS if s != "continuous_exploration"])
@effect(*[f"{s}:coarse_cell_m" for s in EXPLORERS if s != "continuous_exploration"])
def test_robots_start_on_coarse_cells(name: str) -> None:
    for cell in (0.3, 0.6):
        q = explore(name, 0, coarse_cell_m=cell).built.initial.positions
        d = np.linalg.norm(q[:, None] - q[None], axis=-1)[np.triu_indices(len(q), 1)]
        assert d.min() == pytest.approx(cell, abs=0.051)  # centres of neighbouring cells


@BOTH
@effect(*shared("base_m"))
def test_the_base_station_is_where_it_is_asked(name: str) -> None:
    for base in ([2.0, 2.0], [9.0, 13.0]):
        fixed = explore(name, 0, base_m=base).built.initial.fixed[0]
        assert np.linalg.norm(fixed - base) <= 0.3  # the centre of its coarse cell


def link_of(name: str, **params: object):  # noqa: ANN201
    """The link model the run's simulator uses, set from ``params``."""
    return explore(name, 1, **params).built.strategy.sim.link


def reach_cells(link, walls: int = 0) -> float:  # noqa: ANN001
    """The farthest distance (cells) the model links along a row, ``walls`` cells of wall
    halfway between the ends."""
    free = np.ones((2000, 3), dtype=bool)
    d = np.arange(1, 1990, dtype=float)
    a = np.column_stack([np.full_like(d, 1.5), np.full_like(d, 1.5)])
    b = a + np.column_stack([d, np.zeros_like(d)])
    ok = np.zeros(len(d), dtype=bool)
    for k, dk in enumerate(d):  # a wall of ``walls`` cells in the middle of each pair
        mask = free.copy()
        mid = int(1.5 + dk / 2)
        if walls and dk > walls + 2:
            mask[mid : mid + walls, :] = False
        elif walls:
            continue
        ok[k] = link.linked(mask, a[k : k + 1], b[k : k + 1])[0]
    return float(d[ok].max()) if ok.any() else 0.0


@BOTH
@effect(*shared("link_model", "comm_range_m"))
def test_link_model_and_range(name: str) -> None:
    assert reach_cells(link_of(name, comm_range_m=6.0)) == pytest.approx(60, abs=1)
    assert reach_cells(link_of(name, comm_range_m=3.0)) == pytest.approx(30, abs=1)
    assert reach_cells(link_of(name, comm_range_m=6.0), walls=2) == 0  # los: a wall cuts
    assert reach_cells(link_of(name, comm_range_m=6.0, link_model="disk"), walls=2) >= 59


def signal_reach_m(ref_power: float, ref_distance: float, exponent: float, cutoff: float) -> float:
    """The free-space range of the log-distance model, solved by hand."""
    return ref_distance * 10 ** ((ref_power - cutoff) / (10 * exponent))


SIGNAL_KEYS = ("signal.ref_power_dbm", "signal.ref_distance_m", "signal.exponent",
               "signal.cutoff_dbm", "signal.wall_loss_db")  # fmt: skip
NO_EFFECT["silent_exploration:scan_steps"] = (
    "refused unless 1: the steering law never stops a robot at a frontier to scan "
    "(test_silent_exploration_refuses_scans)"
)
NO_EFFECT.update({
    f"silent_exploration:{k}": "the steering law needs a sensing range d_max: "
    "link_model signal is refused (test_silent_exploration_refuses_the_signal_model)"
    for k in SIGNAL_KEYS
})  # fmt: skip


def test_silent_exploration_refuses_the_signal_model() -> None:
    with pytest.raises(ScenarioError, match="link_model: the steering law needs"):
        explore("silent_exploration", 1, link_model="signal")


@pytest.mark.parametrize("name", [s for s in EXPLORERS if s != "silent_exploration"])
@effect(*[f"{s}:{k}" for s in EXPLORERS if s != "silent_exploration" for k in SIGNAL_KEYS])
def test_signal_parameters_set_the_reach(name: str) -> None:
    base = {"ref_power_dbm": -40.0, "ref_distance_m": 1.0, "exponent": 2.5,
            "wall_loss_db": 3.0, "cutoff_dbm": -70.0}  # fmt: skip
    for change in ({}, {"ref_power_dbm": -35.0}, {"ref_distance_m": 0.5}, {"exponent": 3.0},
                   {"cutoff_dbm": -65.0}):  # fmt: skip
        sig = {**base, **change}
        link = link_of(name, link_model="signal", signal=sig)
        want = 10 * signal_reach_m(sig["ref_power_dbm"], sig["ref_distance_m"],
                                   sig["exponent"], sig["cutoff_dbm"])  # fmt: skip
        assert reach_cells(link) == pytest.approx(np.floor(want), abs=1), change
    low = link_of(name, link_model="signal", signal={**base, "wall_loss_db": 1.0})
    high = link_of(name, link_model="signal", signal={**base, "wall_loss_db": 6.0})
    assert reach_cells(low, walls=3) > reach_cells(high, walls=3) > 0


FAILING = [s for s in EXPLORERS if s != "continuous_exploration"]
NO_EFFECT.update({
    f"continuous_exploration:{k}": "refused: robot failures are not modelled by the "
    "continuous controller (test_continuous_exploration_refuses_failures)"
    for k in ("failures.at_s", "failures.random", "failures.window_s")
})  # fmt: skip


def test_continuous_exploration_refuses_failures() -> None:
    with pytest.raises(ScenarioError, match="failures are not modelled"):
        explore("continuous_exploration", 1, failures={"at_s": {1: 5.0}})


@pytest.mark.parametrize("name", FAILING)
@effect(*[f"{s}:failures.at_s" for s in FAILING])
def test_a_robot_fails_at_its_time(name: str) -> None:
    data = for_strategy(name, sim__dt_s=2.0, sim__max_steps=12)
    data["strategy"]["params"]["failures"] = {"at_s": {1: 12.0}}  # step 6 of 2 s
    r = ran(data)
    q = r.positions[:, 1]
    assert np.linalg.norm(np.diff(q[6:], axis=0), axis=1).max() == 0  # stopped from step 6
    assert r.metrics["failures"] == [{"robot": 1, "step": 6}]
    assert np.linalg.norm(np.diff(q[:6], axis=0), axis=1).max() > 0


@pytest.mark.parametrize("name", FAILING)
@effect(*[f"{s}:{k}" for s in FAILING for k in ("failures.random", "failures.window_s")])
def test_random_failures_fall_in_their_window(name: str) -> None:
    for seed in range(3):
        data = for_strategy(name, seed=seed, sim__max_steps=30)
        data["strategy"]["params"]["failures"] = {"random": 2, "window_s": [5.0, 9.0]}
        failed = ran(data).metrics["failures"]
        assert len(failed) == 2
        assert all(5 <= f["step"] <= 9 for f in failed), failed
    assert explore(name, 30).metrics["robots_failed"] == 0


# -- recurrent only --------------------------------------------------------------------


@effect("recurrent:theta")
def test_theta_waits_for_more_ready_robots() -> None:
    assert explore("recurrent", theta=3).metrics["plans"] < explore("recurrent").metrics["plans"]


@effect("recurrent:method", "recurrent:backend")
def test_method_and_backend_pick_the_solver() -> None:
    methods = {
        (m, b): {p.get("method") for p in explore("recurrent", 15, method=m, backend=b)
                 .built.strategy.policy.plans if p.get("issued")}
        for m, b in (("apx", "highs"), ("ilp", "highs"), ("ilp", "scip"))
    }  # fmt: skip
    assert methods == {("apx", "highs"): {"apx"}, ("ilp", "highs"): {"ilp-highs"},
                       ("ilp", "scip"): {"ilp-scip"}}  # fmt: skip


@effect("recurrent:delta")
def test_delta_is_the_apx_parameter(monkeypatch: pytest.MonkeyPatch) -> None:
    import tether.recurrent.replanning as replanning

    seen: list[int] = []
    real = replanning.optimal_configuration

    def spy(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        seen.append(kwargs["delta"])
        return real(*args, **kwargs)

    monkeypatch.setattr(replanning, "optimal_configuration", spy)
    explore("recurrent", 10, delta=2)
    assert seen and set(seen) == {2}
    low = explore("recurrent", delta=1).metrics["plans_not_proven_optimal"]
    assert low >= explore("recurrent", delta=8).metrics["plans_not_proven_optimal"]


@effect("recurrent:time_limit_s")
def test_a_tiny_time_limit_times_the_ilp_out() -> None:
    assert explore("recurrent", 15, method="ilp", time_limit_s=1e-6).metrics["plans_timed_out"] > 0
    assert explore("recurrent", 15, method="ilp").metrics["plans_timed_out"] == 0


@effect("recurrent:count_planning_time")
def test_counting_planning_time_makes_robots_wait() -> None:
    counted = explore("recurrent", count_planning_time=True).metrics["time_waiting_frac"]
    assert counted > 2 * explore("recurrent").metrics["time_waiting_frac"]


@effect("recurrent:check")
def test_check_checks_every_plan(monkeypatch: pytest.MonkeyPatch) -> None:
    import tether.recurrent.replanning as replanning

    calls: list[int] = []
    real = replanning.check_configuration

    def spy(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(replanning, "check_configuration", spy)
    assert explore("recurrent", 15).metrics["constraint_violations"] == 0 and not calls
    plans = explore("recurrent", 15, check=True).metrics["plans"]
    assert len(calls) == plans > 0


@effect("recurrent:relay_binding")
def test_assigned_binding_holds_relays_longer() -> None:
    def relaying(binding: str) -> float:
        data = changed(EXPLORE, team__n_robots=8, sim__max_steps=60)
        data["strategy"]["params"].update(comm_range_m=5.0, relay_binding=binding)
        return ran(data).metrics["time_relaying_frac"]

    assert relaying("assigned") > relaying("frontiers")


# -- utility only ----------------------------------------------------------------------


@effect("utility:ratio")
def test_a_higher_ratio_sends_robots_home_more() -> None:
    returns = [explore("utility", ratio=r).metrics["returns_to_bs"] for r in (0.0, 0.5, 1.0)]
    assert returns[0] == 0 < returns[1] < returns[2], returns


def corridor_map(tmp_path: Path) -> str:
    """A corridor 1 m wide and 25 m long (0.1 m cells) as a PNG: one frontier ahead."""
    occ = np.ones((260, 30), dtype=bool)
    occ[2:252, 10:20] = False
    path = tmp_path / "corridor.png"
    Image.fromarray(np.where(occ, 0, 255).astype(np.uint8).T[::-1]).save(path)
    return str(path)


@pytest.mark.parametrize("name", ["utility", "unconstrained"])
@effect("utility:coordination", "unconstrained:coordination")
def test_coordination_from_yaml_decides_who_takes_the_one_frontier(
    tmp_path: Path, name: str
) -> None:
    from tether.recurrent.exploration.sim import GoalKind

    world = {"scene": "map", "dim": 2, "params": {"path": corridor_map(tmp_path),
                                                   "resolution_m": 0.1}}  # fmt: skip
    goals = {}
    for mode in ("greedy", "none"):
        data = changed(EXPLORE, strategy__name=name, world=world, team__n_robots=3,
                       strategy__params={"coordination": mode, "base_m": [0.6, 1.5]})  # fmt: skip
        sim = ran(data, 1).built.strategy.sim
        goals[mode] = {tuple(g) for g in sim.goal[sim.goal_kind == GoalKind.FRONTIER].tolist()}
        assert (sim.goal_kind == GoalKind.FRONTIER).sum() >= 2
    assert len(goals["none"]) == 1  # every robot on its own: the best frontier for each
    assert len(goals["greedy"]) >= 2  # joint assignment: never two on one frontier goal


@BOTH
@effect(*shared("coverage_goal"))
def test_the_coverage_goal_ends_the_run(name: str) -> None:
    """Once the base station knows the goal's share of the area, the run stops."""
    free = explore(name, 40)
    done = explore(name, 40, coverage_goal=0.02)
    known = explored(free)
    assert known.max() >= 0.02  # the goal is reached within the free run's 40 steps
    assert len(done.positions) < len(free.positions)
    assert done.metrics["mission"]["coverage_goal_reached"] is True
    assert explored(done)[-1] >= 0.02


def leader_and_followers(**params: object) -> Ran:
    return explore("silent_exploration", 30, **params)


@effect("silent_exploration:leader")
def test_the_leader_is_the_robot_that_explores() -> None:
    for leader in (0, 2, 3):
        r = leader_and_followers(leader=leader)
        steps = np.linalg.norm(np.diff(r.positions, axis=0), axis=2)
        moving = (steps > 0).sum(axis=0)  # the followers settle; the leader goes on
        assert (
            int(moving.argmax()) == leader and moving[leader] > 2 * np.delete(moving, leader).max()
        )


@effect("silent_exploration:d0_m", "silent_exploration:gamma")
def test_d0_and_gamma_shape_the_followers_steps() -> None:
    base = leader_and_followers()
    for change in ({"d0_m": 2.0}, {"gamma": 0.05}):
        other = leader_and_followers(**change)
        followers = [i for i in range(4) if i != 0]
        assert not np.allclose(travel(base)[followers], travel(other)[followers]), change
    slow = leader_and_followers(gamma=0.02)
    assert travel(slow)[1:].sum() < travel(base)[1:].sum()  # a smaller gain, shorter steps


@effect("silent_exploration:min_separation_m")
def test_min_separation_keeps_robots_apart() -> None:
    for sep in (0.5, 2.0):
        r = leader_and_followers(min_separation_m=sep)
        q = r.positions[-1]
        d = np.linalg.norm(q[:, None] - q[None], axis=-1)[np.triu_indices(len(q), 1)]
        assert d.min() >= sep - 0.15  # a cell of rounding
