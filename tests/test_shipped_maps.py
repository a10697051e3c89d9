"""Built-in scenarios on maps run from any folder: the maps tether ships and their stand-ins.

The recurrent paper's maps beside the repository cannot be shipped (licence), so the
built-in scenarios name a stand-in that tether generates and ships
(``world.params.stand_in_path``). From a folder where the originals are not found they
run on the stand-in, with one warning; the shipped images are exactly what the
generator makes, so anyone can make them again.
"""

from __future__ import annotations

import fnmatch
import json
from importlib import resources
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from scipy import ndimage

from _cli import tether
from tether.config import builtin_scenarios, load_scenario, paper_campaigns
from tether.world.generated_maps import GENERATED_MAPS, SHAPE_PX
from tether.world.maps import load_map

tomllib = pytest.importorskip("tomllib")

ROOT = Path(__file__).resolve().parents[1]
SHIPPED = ROOT / "src" / "tether" / "scenarios" / "maps"


@pytest.fixture(autouse=True)
def _warn_again(monkeypatch):
    """The stand-in warning is given once per process: forget earlier tests' warnings."""
    from tether import scenario_world

    monkeypatch.setattr(scenario_world, "_WARNED", set())


def _stand_in_names() -> list[str]:
    names = [*builtin_scenarios(), *paper_campaigns()]
    return [n for n in names if "stand_in_path" in load_scenario(n).world.params]


@pytest.mark.parametrize("name", sorted(GENERATED_MAPS))
def test_shipped_map_is_what_the_generator_makes(name):
    shipped = np.asarray(Image.open(SHIPPED / f"{name}.png"))
    made = GENERATED_MAPS[name]()
    assert shipped.shape == made.shape == SHAPE_PX
    np.testing.assert_array_equal(shipped, made)
    assert set(np.unique(made)) == {0, 255}
    _, regions = ndimage.label(made == 255)
    assert regions == 1  # every free cell can reach every other one
    grid = load_map(SHIPPED / f"{name}.png", resolution_m=0.1)
    assert grid.shape == (800, 600) and 0.05 < grid.occupied.mean() < 0.6


def test_every_file_beside_the_scenarios_is_package_data():
    """A file under src/tether/scenarios that no package-data glob names is not installed."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text())
    globs = project["tool"]["setuptools"]["package-data"]["tether"]
    base = ROOT / "src" / "tether"
    files = [p.relative_to(base).as_posix() for p in (base / "scenarios").rglob("*") if p.is_file()]
    missing = [f for f in files if not any(fnmatch.fnmatch(f, g) for g in globs)]
    assert files and missing == []


def test_the_recurrent_builtins_name_a_shipped_stand_in():
    names = _stand_in_names()
    runs = {f"recurrent_{m}" for m in ("grass", "offices", "open", "utility")}
    kinds = ("fig4", "fig5_6", "fig5_6_utility", "relay_binding")
    campaigns = {f"paper/recurrent_{f}" for f in kinds} | {"paper/mission"}
    expect = runs | campaigns
    assert set(names) == expect
    for name in names:
        sc = load_scenario(name)
        stand_in = sc.resolve_path(sc.world.params["stand_in_path"])
        package = resources.files("tether.scenarios") / "maps"
        assert stand_in.resolve() == Path(str(package / stand_in.name)).resolve()


@pytest.mark.parametrize("name", ["recurrent_grass", "paper/recurrent_fig5_6_utility"])
def test_builtin_validates_from_an_empty_folder_on_its_stand_in(capsys, tmp_path, monkeypatch,
                                                                name):  # fmt: skip
    monkeypatch.chdir(tmp_path)
    code, out, err = tether(capsys, "validate", name, "--quick" if "/" in name else "--set=seed=0")
    assert code == 0, err
    warned = [line for line in err.splitlines() if line.startswith("warning:")]
    assert len(warned) == 1 and "not found; running on its stand-in" in warned[0]


def test_builtin_runs_from_an_empty_folder(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, _, err = tether(capsys, "run", "recurrent_offices", "--set", "sim.max_steps=15",
                          "--out", "r", "--no-figures")  # fmt: skip
    assert code == 0, err
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert summary["steps"] == 15 and summary["final_explored_fraction"] > 0


def test_the_original_is_used_where_it_is_found(capsys, tmp_path, monkeypatch):
    """No stand-in (and no warning) when the path itself is found."""
    Image.fromarray(GENERATED_MAPS["open"]()).save(tmp_path / "mine.png")
    monkeypatch.chdir(tmp_path)
    code, _, err = tether(capsys, "validate", "recurrent_grass", "--set",
                          f"world.params.path={tmp_path / 'mine.png'}")  # fmt: skip
    assert code == 0 and "warning" not in err, err


@pytest.mark.parametrize(
    ("sets", "message"),
    [
        (["world.params.stand_in_path=nowhere.png"], "world.params.stand_in_path: nowhere.png: "
         "file not found"),
        (["world.params.stand_in_path=3"], "world.params.stand_in_path: got 3; it must be a file"),
    ],
)  # fmt: skip
def test_bad_stand_ins_are_one_line(capsys, tmp_path, monkeypatch, sets, message):
    monkeypatch.chdir(tmp_path)
    args = [a for s in sets for a in ("--set", s)]
    code, out, err = tether(capsys, "validate", "recurrent_open", *args)
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1, err


def test_a_stand_in_needs_a_path(capsys, tmp_path):
    scenario = tmp_path / "s.yaml"
    scenario.write_text(
        "world: {scene: free, params: {stand_in_path: x.png}}\nteam: {n_robots: 1}\n"
        "sensing: {range_m: 5}\nstrategy: {name: silent, params: {trajectory: "
        "{kind: waypoints, waypoints: [[0, 0], [1, 0]]}}}\n"
    )
    code, _, err = tether(capsys, "validate", str(scenario))
    assert code == 2 and "world.params.stand_in_path: stands in for world.params.path" in err
