"""The recurrent-connectivity strategy in the simulator: every plan satisfies (I)-(IV).

Tiny versions of the paper's runs (small maps, 3-4 robots, ~60 steps); the
full experiment is ``tether report --paper recurrent`` over the paper campaigns' sweeps.
"""

from __future__ import annotations

from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from tether.recurrent.exploration.sim import ExplorationConfig, ExplorationSim, random_base
from tether.recurrent.replanning import RecurrentStrategy

MAPS = Path(__file__).parents[1] / ".." / "shared" / "maps"


def office(seed: int, size=(12.0, 20.0)) -> np.ndarray:
    import tether.world.scenes  # noqa: F401
    from tether.registry import SCENES

    return SCENES.get("office")(np.random.default_rng(seed), dim=2, size_m=list(size)).grid.occupied


def shared_crop(name: str, x0: int, y0: int, w: int = 220, h: int = 180) -> np.ndarray:
    path = MAPS / f"{name}.png"
    if not path.exists():
        pytest.skip(f"{path} not found (the shared maps are test data outside the package)")
    from tether.world.maps import load_map

    occ = load_map(path, occupied_thresh=0.999, free_thresh=0.998).occupied
    return occ[x0 : x0 + w, y0 : y0 + h]


def run(occ, strategy, n=4, steps=60, seed=0, invariant=None):
    cfg = ExplorationConfig(n_robots=n, steps=steps)
    sim = ExplorationSim(occ, random_base(occ, 3, np.random.default_rng(seed)), strategy, cfg)
    strategy.start(sim)
    explored = [sim.explored_fraction()]
    for _ in range(steps):
        sim.step()
        explored.append(sim.explored_fraction())
        if invariant is not None:
            invariant(sim)
    return sim, SimpleNamespace(explored=np.asarray(explored))


def ready_are_connected(sim):
    s = sim.strategy
    keys = s.goal_keys(sim)
    ready = s.tracker.ready(sim.at_goal & sim.scanned, sim.connected, keys)
    assert not (ready & ~sim.connected).any()


@pytest.mark.parametrize(("seed", "theta"), [(0, 1), (1, 1), (2, 2), (3, 4), (4, 3)])
def test_every_plan_satisfies_constraints_office(seed: int, theta: int) -> None:
    strat = RecurrentStrategy(theta=theta, check=True)
    sim, res = run(office(seed), strat, n=4, steps=60, seed=seed, invariant=ready_are_connected)
    issued = [p for p in strat.plans if p["issued"]]
    assert issued, "no plan was issued"
    assert strat.violations == []
    assert res.explored[-1] > res.explored[0]
    assert np.all(np.diff(res.explored) >= 0)


@pytest.mark.parametrize(
    ("name", "x0", "y0"), [("offices", 300, 200), ("grass", 250, 200), ("open", 100, 100)]
)
def test_every_plan_satisfies_constraints_shared_maps(name: str, x0: int, y0: int) -> None:
    occ = shared_crop(name, x0, y0)
    strat = RecurrentStrategy(theta=1, check=True)
    _, res = run(occ, strat, n=4, steps=60, seed=1)
    assert any(p["issued"] for p in strat.plans)
    assert strat.violations == []
    assert res.explored[-1] > res.explored[0]


def test_ilp_plans_satisfy_constraints() -> None:
    pytest.importorskip("highspy")
    strat = RecurrentStrategy(theta=3, method="ilp", backend="highs", check=True)
    _, res = run(office(5), strat, n=3, steps=50, seed=5)
    issued = [p for p in strat.plans if p["issued"]]
    assert issued and all(p["method"].startswith("ilp") for p in issued)
    assert strat.violations == []


def test_recovery_preempts_the_branch() -> None:
    strat = RecurrentStrategy(theta=4, check=True)
    cfg = ExplorationConfig(n_robots=4, steps=40)
    occ = office(7)
    sim = ExplorationSim(occ, random_base(occ, 3, np.random.default_rng(7)), strat, cfg)
    strat.start(sim)
    for _ in range(40):
        sim.step()
        if strat.tracker.obligations and not sim.at_goal.all():
            break
    assert strat.tracker.obligations, "no plan with relay obligations to abort"
    keys = strat.goal_keys(sim)
    victim = next(
        r for r in range(sim.n) if any(int(keys[r]) in o.members for o in strat.tracker.obligations)
    )
    branch = strat.tracker.branch(victim, keys)
    strat.blocked[victim] = True
    sim.step()
    abort = [e for e in sim.events if e["kind"] == "abort"]
    assert abort and set(abort[-1]["preempted"]) == branch
    keys = strat.goal_keys(sim)
    bound = set().union(*(o.members for o in strat.tracker.obligations))
    for r in branch:  # preempted robots stop and are bound by nothing
        assert int(keys[r]) not in bound or any(
            e["kind"] == "plan" and e["step"] == sim.t for e in sim.events
        )


def test_yaml_scenario_writes_run_folder(tmp_path: Path) -> None:
    from tether.config import load_scenario
    from tether.runner import run as run_scenario

    sc = load_scenario("recurrent_demo")
    sc.sim.max_steps = 40
    sc.team.n_robots = 3
    sc.output.figures = False
    out = run_scenario(sc, out_dir=tmp_path / "r")
    s = out.summary
    for key in ("scenario", "strategy", "seed", "n_robots", "sim_time_s", "steps", "wall_time_s"):
        assert key in s
    assert s["strategy"] == "recurrent" and s["steps"] == 40 and s["sim_time_s"] == 40.0
    assert 0 < s["final_explored_fraction"] <= 1
    assert s["constraint_violations"] == 0
    for f in ("summary.json", "steps.parquet", "robots.parquet", "events.parquet"):
        assert (tmp_path / "r" / f).exists()


def test_params_reject_unknown_keys() -> None:
    from pydantic import ValidationError

    from tether.recurrent.strategy import RecurrentParams, UtilityParams

    with pytest.raises(ValidationError):
        RecurrentParams.model_validate({"thetta": 3})
    with pytest.raises(ValidationError):
        UtilityParams.model_validate({"ratio": 2.0})


@pytest.mark.parametrize(
    "name", ["recurrent_grass", "recurrent_offices", "recurrent_open", "recurrent_utility"]
)
def test_real_map_scenarios_are_the_papers_setting(tmp_path: Path, name: str) -> None:
    """The shipped real-map scenarios load the shared map as the report does and run."""
    from tether.config import load_scenario
    from tether.recurrent.strategy import _config
    from tether.registry import STRATEGIES
    from tether.runner import run as run_scenario
    from tether.world.maps import load_map

    path = Path(__file__).parents[1] / "scenarios" / f"{name}.yaml"
    sc = load_scenario(path)
    map_path = sc.resolve_path(sc.world.params["path"])
    if not map_path.exists():
        pytest.skip(f"{map_path} not found (the shared maps are test data outside the package)")
    params = STRATEGIES.get(sc.strategy.name).Params.model_validate(sc.strategy.params)
    cfg = _config(params, sc, sc.world.params["resolution_m"])
    assert cfg == ExplorationConfig()  # 12 robots, 900 steps, 4 cells/step, 50/150 cells
    sc.sim.max_steps = 12
    sc.team.n_robots = 3
    sc.output.figures = False
    s = run_scenario(sc, out_dir=tmp_path / "r").summary
    assert s["map_cells"] == [800, 600] and s["steps"] == 12
    if name != "recurrent_utility":
        assert s["constraint_violations"] == 0
    # same map cells and BS as seed 0 of the paper campaigns
    occ = load_map(map_path, occupied_thresh=0.999, free_thresh=0.998).occupied
    base = random_base(occ, 3, np.random.default_rng(0))
    assert np.allclose(np.asarray(s["base_m"]) / 0.1, base)
