"""Every registered plug-in runs: strategies, scenes and link models (as VMAS tests scenarios).

Each test builds a short scenario around one plug-in, runs it through
``tether.runner.run`` and checks the run folder against the recorded
contract: every table readable, one ``steps`` row per step, links on existing
nodes, the core summary keys present and consistent with the records.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.parquet as pq
import pytest
from PIL import Image

from tether.config import builtin_scenarios, load_scenario, scenario_from_dict
from tether.plugins import load_builtins
from tether.record import CORE_KEYS
from tether.registry import LINK_MODELS, SCENES, STRATEGIES
from tether.runner import run
from tether.world.scenes import free_positions, make_scene

load_builtins()


def check_run_folder(path: Path, n_robots: int) -> dict[str, Any]:
    """The run folder contract of the README; returns the summary."""
    summary = json.loads((path / "summary.json").read_text())
    for key in (*CORE_KEYS, "connected_all_steps", "min_links", "collisions", "provenance"):
        assert key in summary, key
    steps = pq.read_table(path / "steps.parquet").to_pydict()
    assert steps["step"] == list(range(summary["steps"] + 1))
    assert all(c in steps for c in ("t_s", "connected", "n_links", "lambda2", "collisions"))
    assert summary["connected_all_steps"] == all(steps["connected"])
    assert summary["min_links"] == min(steps["n_links"])
    robots = pq.read_table(path / "robots.parquet").to_pydict()
    assert set(robots["robot"]) == set(range(n_robots))
    assert np.isfinite(robots["x_m"]).all()
    links = pq.read_table(path / "links.parquet").to_pydict()
    n_nodes = n_robots + (1 if "base_m" in summary else 0)  # a base station is a fixed node
    assert all(0 <= i < j < n_nodes for i, j in zip(links["i"], links["j"], strict=True))
    pq.read_table(path / "events.parquet")
    assert summary["n_robots"] == n_robots
    return summary


def builtin_using(strategy: str) -> list[str]:
    return [s for s in builtin_scenarios() if load_scenario(s).strategy.name == strategy]


def shortened(name: str, steps: int) -> dict[str, Any]:
    data = load_scenario(name).model_dump(mode="json")
    data["sim"]["max_steps"] = steps
    data["output"]["figures"] = True
    return data


@pytest.mark.parametrize("strategy", STRATEGIES.names())
def test_every_strategy_runs_a_builtin_scenario(strategy, tmp_path, skip_without_shared_map):
    names = builtin_using(strategy)
    assert names, f"strategy {strategy!r} has no built-in scenario"
    sc = scenario_from_dict(shortened(names[0], 8), names[0], load_scenario(names[0]).base_dir)
    skip_without_shared_map(sc)
    outcome = run(sc, out_dir=tmp_path / strategy)
    check_run_folder(outcome.path, sc.team.n_robots)
    assert (outcome.path / "figures" / "links.png").exists()


def scene_params(scene: str, tmp_path: Path) -> dict[str, Any]:
    if scene == "map":
        img = np.full((40, 60), 255, np.uint8)
        img[0, :] = img[-1, :] = img[:, 0] = img[:, -1] = 0
        img[20, 10:40] = 0
        Image.fromarray(img).save(tmp_path / "room.png")
        return {"path": str(tmp_path / "room.png"), "resolution_m": 0.25}
    if scene == "user_points":
        np.save(tmp_path / "pts.npy", np.array([[5.0, 5.0], [5.0, 6.0], [6.0, 5.0]]))
        return {"path": str(tmp_path / "pts.npy"), "resolution_m": 0.5, "margin_m": 8.0}
    return {}


@pytest.mark.parametrize("scene", SCENES.names())
def test_every_scene_hosts_a_short_run(scene, tmp_path):
    """Two robots in free space of the scene, the silent strategy for five steps."""
    params = scene_params(scene, tmp_path)
    world = make_scene(scene, np.random.default_rng(0), **params)
    rng = np.random.default_rng(1)
    if world.bounds_m is None:
        start = np.zeros(world.dim)
    else:
        start = free_positions(world, 1, rng, clearance_m=1.0, same_component=True)[0]
    offset = np.zeros(world.dim)
    offset[0] = 0.3
    pair = [start.tolist(), (start + offset).tolist()]
    data = {
        "name": f"scene-{scene}",
        "world": {"scene": scene, "dim": world.dim, "params": params},
        "team": {"n_robots": 2, "init": {"kind": "positions", "positions": pair}},
        "sensing": {"range_m": 3.0},
        "sim": {"max_steps": 5},
        "strategy": {"name": "silent", "params": {"d0_m": 1.0, "trajectory": {
            "waypoints": pair, "speed_mps": 0.1}}},
        "output": {"figures": False},
    }  # fmt: skip
    outcome = run(scenario_from_dict(data, f"{scene}.yaml"), out_dir=tmp_path / "run")
    summary = check_run_folder(outcome.path, 2)
    assert summary["connected_all_steps"]


@pytest.mark.parametrize("model", LINK_MODELS.names())
def test_every_link_model_runs_the_exploration_demo(model, tmp_path):
    data = shortened("recurrent_demo", 12)
    data["strategy"]["params"]["link_model"] = model
    outcome = run(scenario_from_dict(data, "demo.yaml"), out_dir=tmp_path / model)
    summary = check_run_folder(outcome.path, data["team"]["n_robots"])
    assert 0 < summary["final_explored_fraction"] <= 1


def test_cli_list_names_every_registered_plugin():
    from typer.testing import CliRunner

    from tether.cli import app

    result = CliRunner().invoke(app, ["list"])
    assert result.exit_code == 0, result.output
    text = " ".join(result.output.split())
    for name in (*STRATEGIES.names(), *SCENES.names(), *LINK_MODELS.names(), *builtin_scenarios()):
        assert name in text
