"""A corpus of bad inputs: every one ends in exit code 2 and one line naming file and field.

Each scenario-file case is run through ``tether validate`` and ``tether run``
(in-process, through :func:`tether.cli.main`): both must exit with code 2,
print exactly one ``error:`` line on stderr naming the file and the field, print
the *same* line (validate and run agree), print no traceback, and leave no run
folder behind. Command-line cases (usage errors, bad options, bad ``--out``)
check the same one-line contract. A few cases run as real subprocesses at the
end, to show the installed entry point behaves as the in-process one.
"""

from __future__ import annotations

import os
import struct
import subprocess
import sys
import zlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
import yaml
from PIL import Image

from _cli import tether
from tether import cli
from tether.config import load_scenario

# --------------------------------------------------------------------------- harness


def assert_one_line(code: int, err: str, *needles: str) -> str:
    assert code == 2, err
    assert "Traceback" not in err, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    line = lines[0]
    assert line.startswith("error: "), line
    assert "internal error" not in line, line
    for needle in needles:
        assert needle in line, f"{needle!r} not in {line!r}"
    return line


# --------------------------------------------------------------------------- bases


def _builtin(name: str) -> dict[str, Any]:
    scenario = load_scenario(name)
    return yaml.safe_load((scenario.base_dir / f"{name}.yaml").read_text())


def silent(tmp: Path) -> dict[str, Any]:
    return _builtin("silent_demo")


def connectivity(tmp: Path) -> dict[str, Any]:
    return _builtin("connectivity_empty")


def _png(path: Path, pixels: np.ndarray) -> Path:
    Image.fromarray(pixels.astype(np.uint8)).save(path)
    return path


def recurrent(tmp: Path) -> dict[str, Any]:
    """A small exploration scenario on a 6 m x 4 m map (walls around, one inner wall)."""
    img = np.full((40, 60), 255, dtype=np.uint8)
    img[[0, -1], :] = 0
    img[:, [0, -1]] = 0
    img[:25, 30] = 0
    _png(tmp / "room.png", img)
    return {
        "name": "room",
        "world": {"scene": "map", "dim": 2, "params": {"path": "room.png", "resolution_m": 0.1}},
        "team": {"n_robots": 3},
        "sensing": {"range_m": 2.0},
        "sim": {"dt_s": 1.0, "max_steps": 20},
        "strategy": {"name": "recurrent", "params": {"theta": 1, "speed_m_s": 0.4}},
    }


def utility(tmp: Path) -> dict[str, Any]:
    data = recurrent(tmp)
    data["strategy"] = {"name": "utility", "params": {"ratio": 0.5}}
    return data


def wall_map(tmp: Path) -> dict[str, Any]:
    img = np.full((40, 60), 255, dtype=np.uint8)
    img[:, 30] = 0  # a vertical wall at x = 30 m
    _png(tmp / "wall.png", img)
    return {"scene": "map", "dim": 2, "params": {"path": "wall.png", "resolution_m": 1.0}}


def huge_png_header(path: Path, width: int, height: int) -> None:
    """A PNG that claims width x height pixels in a few bytes (a decompression bomb)."""

    def chunk(kind: bytes, data: bytes) -> bytes:
        return (
            struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))
        )

    ihdr = struct.pack(">IIBBBBB", width, height, 8, 0, 0, 0, 0)
    idat = zlib.compress(b"\x00" * 16)
    path.write_bytes(
        b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", ihdr) + chunk(b"IDAT", idat) + chunk(b"IEND", b"")
    )


# --------------------------------------------------------------------------- the corpus

Mutation = Callable[[dict[str, Any], Path], Any]


@dataclass(frozen=True)
class Case:
    """A bad scenario: ``base`` data changed by ``mutate``, or raw ``text`` for the file."""

    field: str  # must appear in the one error line (the field, or the file's own name)
    mutate: Mutation | None = None
    base: Callable[[Path], dict[str, Any]] = silent
    text: bytes | None = None
    args: tuple[str, ...] = ()  # extra arguments for both validate and run (--set ...)


def _set(path: str, value: Any) -> Mutation:
    def mutate(d: dict[str, Any], tmp: Path) -> None:
        node = d
        keys = path.split(".")
        for key in keys[:-1]:
            node = node.setdefault(key, {})
        node[keys[-1]] = value

    return mutate


def _all(*mutations: Mutation) -> Mutation:
    def mutate(d: dict[str, Any], tmp: Path) -> None:
        for m in mutations:
            m(d, tmp)

    return mutate


def _map_file(name: str, make: Callable[[Path], Any], **params: Any) -> Mutation:
    """World = a map file made by ``make(path)``."""

    def mutate(d: dict[str, Any], tmp: Path) -> None:
        make(tmp / name)
        d["world"] = {"scene": "map", "dim": 2, "params": {"path": name, **params}}

    return mutate


def _ros_yaml(body: str, image: bool = True) -> Mutation:
    def mutate(d: dict[str, Any], tmp: Path) -> None:
        if image:
            _png(tmp / "img.png", np.full((20, 20), 255))
        (tmp / "m.yaml").write_text(body)
        d["world"] = {"scene": "map", "dim": 2, "params": {"path": "m.yaml"}}

    return mutate


def _recurrent_map(pixels: np.ndarray, resolution_m: float = 0.1) -> Mutation:
    def mutate(d: dict[str, Any], tmp: Path) -> None:
        _png(tmp / "room.png", pixels)
        d["world"]["params"]["resolution_m"] = resolution_m

    return mutate


BOMB = b"""name: bomb
a: &a [x, x, x, x, x, x, x, x, x, x]
b: &b [*a, *a, *a, *a, *a, *a, *a, *a, *a, *a]
c: &c [*b, *b, *b, *b, *b, *b, *b, *b, *b, *b]
d: &d [*c, *c, *c, *c, *c, *c, *c, *c, *c, *c]
e: &e [*d, *d, *d, *d, *d, *d, *d, *d, *d, *d]
f: &f [*e, *e, *e, *e, *e, *e, *e, *e, *e, *e]
g: &g [*f, *f, *f, *f, *f, *f, *f, *f, *f, *f]
"""


def _sweep_bomb(d: dict[str, Any], tmp: Path) -> bytes:
    body = yaml.safe_dump(d)
    return (
        body.encode()
        + b"""sweep:
  strategy.params.gamma: &s0 [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0]
  sensing.range_m: &s1 [*s0, *s0, *s0, *s0, *s0, *s0, *s0, *s0, *s0, *s0]
  sim.dt_s: &s2 [*s1, *s1, *s1, *s1, *s1, *s1, *s1, *s1, *s1, *s1]
  sim.max_steps: &s3 [*s2, *s2, *s2, *s2, *s2, *s2, *s2, *s2, *s2, *s2]
  team.n_robots: &s4 [*s3, *s3, *s3, *s3, *s3, *s3, *s3, *s3, *s3, *s3]
  seed: &s5 [*s4, *s4, *s4, *s4, *s4, *s4, *s4, *s4, *s4, *s4]
  name: [*s5, *s5, *s5, *s5, *s5, *s5, *s5, *s5, *s5, *s5]
"""
    )


CASES: dict[str, Case] = {
    # ---- the file itself
    "not yaml": Case("not valid YAML", text=b"name: [unclosed\n"),
    "not utf-8": Case("not UTF-8", text=b"name: caf\xe9\xff\nseed: 1\n"),
    "top level is a list": Case("(top level)", text=b"- 1\n- 2\n"),
    "empty file": Case("(top level)", text=b""),
    "alias bomb at top level": Case("YAML aliases", text=BOMB),
    "alias bomb in the sweep block": Case("sweep: YAML aliases", mutate=_sweep_bomb),
    "recursive alias": Case("loop", text=b"name: &a [*a]\n"),
    "nested too deeply": Case("nested too deeply", text=b"name: " + b"[" * 5000 + b"]" * 5000),
    # ---- schema: keys and types
    "unknown key": Case("sensing.rnage_m", _set("sensing.rnage_m", 3)),
    "wrong type": Case("team.n_robots", _set("team.n_robots", "many")),
    "missing section": Case("sensing", lambda d, t: d.pop("sensing")),
    "seed negative": Case("seed", _set("seed", -1)),
    "seed too large": Case("seed", _set("seed", 2**64)),
    "name with a slash": Case("name", _set("name", "a/b")),
    # ---- numbers: finite and physical
    "negative range": Case("sensing.range_m", _set("sensing.range_m", -3)),
    "infinite range": Case("sensing.range_m", _set("sensing.range_m", float("inf"))),
    "1e308 range": Case("sensing.range_m", _set("sensing.range_m", 1e308)),
    "NaN range": Case("sensing.range_m", _set("sensing.range_m", float("nan"))),
    "dt inf": Case("sim.dt_s", _set("sim.dt_s", float("inf"))),
    "dt zero": Case("sim.dt_s", _set("sim.dt_s", 0)),
    "max_steps huge": Case("sim.max_steps", _set("sim.max_steps", 10**12)),
    "collision distance NaN": Case(
        "sim.collision_distance_m", _set("sim.collision_distance_m", float("nan"))
    ),
    "spacing 1e308": Case("team.init.spacing_m", _set("team.init.spacing_m", 1e308)),
    "spacing inf": Case("team.init.spacing_m", _set("team.init.spacing_m", float("inf"))),
    "min separation NaN": Case(
        "team.init.min_separation_m", _set("team.init.min_separation_m", float("nan"))
    ),
    "center NaN": Case("team.init.center", _set("team.init.center", [float("nan"), 0.0])),
    "center 3 numbers in 2-D": Case("team.init", _set("team.init.center", [0.0, 0.0, 0.0])),
    "no robots": Case("team.n_robots", _set("team.n_robots", 0)),
    "a billion robots": Case("team.n_robots", _set("team.n_robots", 10**9)),
    "radial error above range": Case("sensing", _set("sensing.radial_error_m", 20.0)),
    "angular error 90 deg": Case(
        "sensing.angular_error_deg", _set("sensing.angular_error_deg", 90)
    ),
    "unknown noise": Case("sensing.noise", _set("sensing.noise", "gaussian")),
    "negative body radius": Case("sensing.body_radius_m", _set("sensing.body_radius_m", -0.1)),
    "record_every 0": Case("output.record_every", _set("output.record_every", 0)),
    "world dim 4": Case("world.dim", _set("world.dim", 4)),
    # ---- the team
    "team not connected": Case(
        "team.init", _all(_set("team.init.kind", "grid"), _set("team.init.spacing_m", 40.0))
    ),
    "team cannot be placed": Case(
        "team.init",
        _all(
            _set("world", {"scene": "free", "dim": 2, "params": {"bounds_m": [[-3, -3], [3, 3]]}}),
            _set("team.n_robots", 200),
        ),
    ),
    "uniform without extent": Case("team.init", _set("team.init.kind", "uniform")),
    "uniform: 100,000 robots 2 m apart in a 40 m box (refused before any draw)": Case(
        "team.init.extent_m",
        _all(
            _set("team.n_robots", 100_000),
            _set(
                "team.init", {"kind": "uniform", "extent_m": [40.0, 40.0], "min_separation_m": 2.0}
            ),
        ),
    ),
    "uniform: 1,000,000 robots in a 40 m box (about 2e10 links to list)": Case(
        "team.init.extent_m",
        _all(
            _set("team.n_robots", 1_000_000),
            _set("team.init", {"kind": "uniform", "extent_m": [40.0, 40.0]}),
        ),
    ),
    "positions of the wrong shape": Case(
        "team.init",
        _all(_set("team.init.kind", "positions"), _set("team.init.positions", [[0, 0], [1, 1]])),
    ),
    "positions NaN": Case(
        "team.init.positions",
        _all(
            _set("team.init.kind", "positions"),
            _set("team.init.positions", [[0, 0]] * 11 + [[float("nan"), 1]]),
        ),
    ),
    "team center inside an obstacle": Case(
        "team.init",
        _all(
            lambda d, t: d.update(world=wall_map(t)),
            _set("team.init.center", [30.5, 20.0]),
        ),
    ),
    "100,000 robots (placement bounded, memory refused)": Case(
        "team.n_robots", _set("team.n_robots", 100_000)
    ),
    # ---- the strategy
    "unknown strategy": Case("strategy.name", _set("strategy.name", "telepathy")),
    "negative gain": Case("strategy.params.gamma", _set("strategy.params.gamma", -1)),
    "misspelled strategy key": Case("strategy.params.gama", _set("strategy.params.gama", 0.1)),
    "NaN waypoint": Case(
        "strategy.params.trajectory.waypoints",
        _set("strategy.params.trajectory.waypoints", [[0, 0], [float("nan"), 0]]),
    ),
    "waypoints in 3-D for a 2-D world": Case(
        "strategy.params.trajectory.waypoints",
        _set("strategy.params.trajectory.waypoints", [[0, 0, 0], [10, 0, 0]]),
    ),
    "one waypoint": Case(
        "strategy.params.trajectory", _set("strategy.params.trajectory.waypoints", [[0, 0]])
    ),
    "waypoint 1e308": Case(
        "strategy.params.trajectory.waypoints",
        _set("strategy.params.trajectory.waypoints", [[0, 0], [1e308, 0]]),
    ),
    "leader path through an obstacle": Case(
        "strategy.params.trajectory",
        _all(
            lambda d, t: d.update(world=wall_map(t)),
            _set("team.init.center", [10.0, 20.0]),
            _set("team.init.spacing_m", 5.0),
            _set("strategy.params.trajectory.waypoints", [[10, 20], [50, 20]]),
        ),
    ),
    "leader index out of range": Case("strategy.params.leader", _set("strategy.params.leader", 12)),
    "trajectory function not importable": Case(
        "strategy.params.trajectory.function",
        _set("strategy.params.trajectory", {"kind": "function", "function": "nowhere.mod:f"}),
    ),
    "speed NaN": Case(
        "strategy.params.trajectory.speed_mps",
        _set("strategy.params.trajectory.speed_mps", float("nan")),
    ),
    "connectivity: NaN range": Case(
        "strategy.params.rs_m", _set("strategy.params.rs_m", float("nan")), base=connectivity
    ),
    "connectivity: unknown preset": Case(
        "strategy.params.preset", _set("strategy.params.preset", "moon"), base=connectivity
    ),
    "connectivity: radii out of order": Case(
        "strategy.params",
        _all(_set("strategy.params.rs_inner_m", 9.0), _set("strategy.params.rs_m", 5.0)),
        base=connectivity,
    ),
    "connectivity: goal for a robot that does not exist": Case(
        "strategy.params.external.robots",
        _set("strategy.params.external.robots", [99]),
        base=connectivity,
    ),
    "connectivity: goal with 2 coordinates in 3-D": Case(
        "strategy.params.external.goals",
        _set("strategy.params.external.goals", [[40, 50]]),
        base=connectivity,
    ),
    # ---- worlds and map files
    "scene height inf": Case(
        "height_m", _set("world", {"scene": "empty", "dim": 3, "params": {"height_m": 1e400}})
    ),
    "scene seed negative": Case("seed", _set("world.params", {"seed": -1})),
    "map scene without a path": Case("world.params.path", _set("world.scene", "map")),
    "unknown scene": Case("world.scene", _set("world.scene", "mars")),
    "unknown scene parameter": Case(
        "world.params", _set("world.params", {"bounds": [[0, 0], [1, 1]]})
    ),
    "scene too fine to fit in memory": Case(
        "resolution_m",
        _set("world", {"scene": "empty", "dim": 3, "params": {"resolution_m": 1e-6}}),
    ),
    "missing map": Case(
        "nope.png", _set("world", {"scene": "map", "dim": 2, "params": {"path": "nope.png"}})
    ),
    "corrupt map": Case("corrupt.png", _map_file("corrupt.png", lambda p: p.write_bytes(b"junk"))),
    "map decompression bomb": Case(
        "bomb.png", _map_file("bomb.png", lambda p: huge_png_header(p, 200_000, 200_000))
    ),
    "PGM truncated": Case(
        "cut.pgm", _map_file("cut.pgm", lambda p: p.write_bytes(b"P5 100000 100000 255\n\x00"))
    ),
    "map given in 3-D": Case(
        "world.dim", _all(lambda d, t: d.update(world=wall_map(t)), _set("world.dim", 3))
    ),
    "ROS map: negative resolution": Case(
        "resolution", _ros_yaml("image: img.png\nresolution: -1\norigin: [0, 0, 0]\n")
    ),
    "ROS map: NaN origin": Case(
        "origin", _ros_yaml("image: img.png\nresolution: 0.1\norigin: [.nan, 0, 0]\n")
    ),
    "ROS map: origin far away": Case(
        "origin", _ros_yaml("image: img.png\nresolution: 0.1\norigin: [1.0e+300, 0, 0]\n")
    ),
    "ROS map: image missing": Case(
        "image", _ros_yaml("image: none.png\nresolution: 0.1\norigin: [0, 0, 0]\n", image=False)
    ),
    # ---- exploration strategies (recurrent, utility)
    "recurrent: misspelled key": Case(
        "strategy.params.thetta", _set("strategy.params.thetta", 2), base=recurrent
    ),
    "recurrent: NaN speed": Case(
        "strategy.params.speed_m_s", _set("strategy.params.speed_m_s", float("nan")), base=recurrent
    ),
    "recurrent: more random failures than robots": Case(
        "strategy.params.failures.random",
        _set("strategy.params.failures", {"random": 99}),
        base=recurrent,
    ),
    "recurrent: all-black map": Case("world", _recurrent_map(np.zeros((40, 60))), base=recurrent),
    "recurrent: 1x1 map": Case("world", _recurrent_map(np.full((1, 1), 255)), base=recurrent),
    "recurrent: range 1e308": Case(
        "sensing.range_m", _set("sensing.range_m", 1e308), base=recurrent
    ),
    "recurrent: 100,000 robots": Case(
        "team.n_robots", _set("team.n_robots", 100_000), base=recurrent
    ),
    "recurrent: base station outside the map": Case(
        "strategy.params.base_m", _set("strategy.params.base_m", [500.0, 500.0]), base=recurrent
    ),
    "recurrent: base station given in 3-D": Case(
        "strategy.params.base_m", _set("strategy.params.base_m", [1.0, 1.0, 1.0]), base=recurrent
    ),
    "recurrent: unknown link model": Case(
        "strategy.params.link_model",
        _set("strategy.params.link_model", "telepathy"),
        base=recurrent,
    ),
    "recurrent: coarse cell larger than the map": Case(
        "strategy.params.coarse_cell_m",
        _set("strategy.params.coarse_cell_m", 100.0),
        base=recurrent,
    ),
    "recurrent: sensor resolution too fine": Case(
        "strategy.params.sensor_resolution_deg",
        _set("strategy.params.sensor_resolution_deg", 1e-9),
        base=recurrent,
    ),
    "recurrent: 3-D world": Case(
        "world", _set("world", {"scene": "free", "dim": 3}), base=recurrent
    ),
    "utility: ratio above 1": Case(
        "strategy.params.ratio", _set("strategy.params.ratio", 2), base=utility
    ),
    # ---- the sweep block (validate and run refuse what `tether sweep` could not run)
    "sweep: unknown axis": Case("sweep.sensing.rnage_m", _set("sweep", {"sensing.rnage_m": [1]})),
    "sweep: unknown strategy parameter": Case(
        "sweep.strategy.params.d0", _set("sweep", {"strategy.params.d0": [5.0, 8.0]})
    ),
    "sweep: unknown scene parameter": Case(
        "sweep.world.params.size", _set("sweep", {"world.params.size": [1, 2]})
    ),
    "sweep: empty axis": Case("sweep.sensing.range_m", _set("sweep", {"sensing.range_m": []})),
    "sweep: axis not a list": Case("sweep.sensing.range_m", _set("sweep", {"sensing.range_m": 5})),
    "sweep: bad value": Case("sweep.sensing.range_m", _set("sweep", {"sensing.range_m": [5, -1]})),
    "sweep: 15.0 and '15.0'": Case(
        "sweep.sensing.range_m", _set("sweep", {"sensing.range_m": [15.0, "15.0"]})
    ),
    "sweep: too many combinations": Case(
        "sweep",
        _set(
            "sweep",
            {
                f"strategy.params.{k}": np.linspace(0.1, 1, 30).tolist()
                for k in ("gamma", "d0_m", "min_separation_m")
            },
        ),
    ),
    "estimator: a billion rounds per sub-step": Case(
        "strategy.params.estimator.rounds_per_substep",
        _set("strategy.params.estimator", {"rounds_per_substep": 1_000_000_000}),
        base=connectivity,
    ),
    "estimator: messages delayed a billion rounds": Case(
        "strategy.params.estimator.delay_rounds",
        _set("strategy.params.estimator", {"delay_rounds": 1_000_000_000}),
        base=connectivity,
    ),
    "multi_target: a billion message rounds per step": Case(
        "strategy.params.messages.rounds_per_step",
        _set("strategy.params.messages", {"rounds_per_step": 1_000_000_000}),
        base=lambda tmp: _builtin("multi_target_empty"),
    ),
    "sweep: a billion seeds (refused before any list is made)": Case(
        "sweep.seeds",
        _set("sweep", {"strategy.params.d0_m": [5.0, 8.0], "seeds": 1_000_000_000}),
    ),
    "sweep: too many trials (2 combinations x 60,000 seeds)": Case(
        "sweep.seeds", _set("sweep", {"strategy.params.d0_m": [5.0, 8.0], "seeds": 60_000})
    ),
    # ---- --set on the command line (validate and run alike)
    "--set unclosed YAML": Case("--set sensing.range_m", args=("--set", "sensing.range_m=[x")),
    "--set without =": Case("--set", args=("--set", "sensing.range_m")),
    "--set empty key": Case("--set", args=("--set", "=5")),
    "--set empty key part": Case("--set", args=("--set", "sensing..range_m=5")),
    "--set inf": Case("sensing.range_m", args=("--set", "sensing.range_m=.inf")),
    "--set replaces a section by a number": Case("sensing", args=("--set", "sensing=5")),
    "--set unknown key": Case("sim.dtt_s", args=("--set", "sim.dtt_s=1")),
}


def _write_case(case: Case, tmp: Path) -> Path:
    path = tmp / "bad.yaml"
    if case.text is not None:
        path.write_bytes(case.text)
        return path
    data = case.base(tmp)
    if case.mutate is not None:
        raw = case.mutate(data, tmp)
        if isinstance(raw, bytes):
            path.write_bytes(raw)
            return path
    path.write_text(yaml.safe_dump(data))
    return path


def test_the_corpus_is_large_enough():
    assert len(CASES) + len(COMMAND_LINES) + len(OUT_CASES) >= 60


@pytest.mark.parametrize("name", list(CASES))
def test_validate_and_run_refuse_with_the_same_line(name, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    case = CASES[name]
    path = _write_case(case, tmp_path)
    code, _, err = tether(capsys, "validate", str(path), *case.args)
    line = assert_one_line(code, err, case.field)
    if not case.field.startswith("--set"):
        assert "bad.yaml" in line
    code, _, err_run = tether(capsys, "run", str(path), "--out", "out", "--no-figures", *case.args)
    assert assert_one_line(code, err_run, case.field) == line  # validate and run agree
    assert not (tmp_path / "out").exists()
    if name.startswith("sweep:"):  # `tether sweep` refuses the same, before any trial
        code, _, err_sweep = tether(capsys, "sweep", str(path), "--out", "sw", *case.args)
        assert assert_one_line(code, err_sweep, case.field) == line
        assert not (tmp_path / "sw").exists()
    assert not [p for p in tmp_path.iterdir() if ".staging" in p.name]


def test_good_versions_of_the_bases_validate(tmp_path, capsys, monkeypatch):
    """The corpus's bases are valid: each bad case is bad because of its one change."""
    monkeypatch.chdir(tmp_path)
    for base in (silent, connectivity, recurrent, utility):
        path = tmp_path / "good.yaml"
        path.write_text(yaml.safe_dump(base(tmp_path)))
        code, out, err = tether(capsys, "validate", str(path))
        assert code == 0, err
        assert "ok" in out


# --------------------------------------------------------------------------- command lines

COMMAND_LINES: dict[str, tuple[tuple[str, ...], str]] = {
    "no arguments": ((), "Missing command"),
    "unknown command": (("fly",), "No such command 'fly'"),
    "run --seed abc": (("run", "--seed", "abc"), "--seed"),
    "run --seed -1": (("run", "--seed", "-1"), "--seed"),
    "run --seed 2**64": (("run", "--seed", str(2**64)), "--seed"),
    "run unknown option": (("run", "--bogus"), "--bogus"),
    "run --no-figures true": (("run", "--no-figures", "true"), "--no-figures"),
    "run --out without value": (("run", "--out"), "--out"),
    "validate without scenario": (("validate",), "scenario"),
    "validate missing file": (("validate", "nowhere.yaml"), "nowhere.yaml: file not found"),
    "run a folder": (("run", "."), "is a folder"),
    "run two scenarios": (("run", "silent_demo", "silent_paper"), "silent_paper"),
    "sweep --seeds 0": (("sweep", "silent_paper", "--seeds", "0"), "--seeds"),
    "sweep --seeds -3": (("sweep", "silent_paper", "--seeds", "-3"), "--seeds"),
    "sweep --workers 0": (("sweep", "silent_paper", "--workers", "0"), "--workers"),
    "sweep unknown executor": (("sweep", "silent_paper", "--executor", "spark"), "spark"),
    "sweep --address without dask": (
        ("sweep", "silent_paper", "--address", "tcp://127.0.0.1:9"),
        "--address",
    ),
    "sweep too many trials": (("sweep", "silent_paper", "--seeds", "10000000"), "sweep"),
    "animate a missing run folder": (("animate", "nowhere"), "nowhere: not a run folder"),
    "animate --stride 0": (("animate", "nowhere", "--stride", "0"), "--stride"),
    "animate --width 0": (("animate", "nowhere", "--width", "0"), "--width"),
    "view --port -5": (("view", "nowhere", "--serve", "--port", "-5"), "--port"),
    "export a missing run folder": (("export", "nowhere"), "nowhere"),
}


@pytest.mark.parametrize("name", list(COMMAND_LINES))
def test_command_line_errors_are_one_line(name, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    args, needle = COMMAND_LINES[name]
    code, _, err = tether(capsys, *args)
    assert_one_line(code, err, needle)
    assert not (tmp_path / "runs").exists()


def test_a_dead_dask_address_fails_fast_in_one_line(tmp_path, capsys, monkeypatch):
    pytest.importorskip("distributed")
    monkeypatch.chdir(tmp_path)
    import socket
    import time

    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    start = time.perf_counter()
    code, _, err = tether(
        capsys,
        "sweep",
        "silent_paper",
        "--out",
        "sw",
        "--executor",
        "dask",
        "--address",
        f"tcp://127.0.0.1:{port}",
    )
    assert time.perf_counter() - start < 20
    assert_one_line(code, err, f"--address tcp://127.0.0.1:{port}", "dask scheduler")


# --------------------------------------------------------------------------- --out


def _ro_dir(tmp: Path) -> str:
    return "/proc/tether-cannot-write/run"


OUT_CASES: dict[str, Callable[[Path], str]] = {
    "a file": lambda t: (t / "f.txt").write_text("x") and "f.txt",
    "under a file": lambda t: (t / "f.txt").write_text("x") and "f.txt/run",
    "read-only place": _ro_dir,
    "non-empty folder of other files": lambda t: (
        (
            (t / "mine").mkdir(),
            (t / "mine" / "notes.txt").write_text("keep me"),
        )
        and "mine"
    ),
    "name too long": lambda t: "x" * 300,
}


@pytest.mark.parametrize("name", list(OUT_CASES))
@pytest.mark.parametrize("command", ["run", "sweep"])
def test_bad_out_is_one_line_and_leaves_nothing(name, command, tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    scenario = tmp_path / "s.yaml"
    data = silent(tmp_path)
    data["sim"]["max_steps"] = 3
    scenario.write_text(yaml.safe_dump(data))
    out = OUT_CASES[name](tmp_path)
    before = sorted(p.name for p in tmp_path.rglob("*"))
    args = ["--no-figures"] if command == "run" else []
    code, _, err = tether(capsys, command, str(scenario), "--out", out, *args)
    assert_one_line(code, err, "--out")
    after = sorted(p.name for p in tmp_path.rglob("*"))
    assert after == before  # no run folder, no staging folder, no parent folder left


def test_an_unwritable_output_dir_is_refused_by_validate_and_run(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "f.txt").write_text("x")
    data = silent(tmp_path)
    data["output"] = {"dir": "f.txt/runs"}
    (tmp_path / "bad.yaml").write_text(yaml.safe_dump(data))
    for command in ("validate", "run"):
        code, _, err = tether(capsys, command, "bad.yaml")
        assert_one_line(code, err, "f.txt/runs", "cannot create")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.yaml", "f.txt"]
    code, out, err = tether(capsys, "validate", "silent_demo")  # a valid one leaves nothing
    assert code == 0 and "ok" in out, err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["bad.yaml", "f.txt"]


def test_rerun_into_the_same_out_replaces_the_folder(tmp_path, capsys, monkeypatch):
    """Reusing --out never mixes two runs' files: the second run replaces the first whole."""
    monkeypatch.chdir(tmp_path)
    short = silent(tmp_path)
    short["sim"]["max_steps"] = 3
    (tmp_path / "a.yaml").write_text(yaml.safe_dump(short))
    code, _, err = tether(capsys, "run", "a.yaml", "--out", "out")
    assert code == 0, err
    assert (tmp_path / "out" / "figures" / "links.png").exists()
    (tmp_path / "out" / "stray.txt").write_text("left by hand")
    code, _, err = tether(capsys, "run", "a.yaml", "--out", "out", "--no-figures")
    assert code == 0, err
    names = {p.name for p in (tmp_path / "out").iterdir()}
    assert "figures" not in names and "stray.txt" not in names
    assert "summary.json" in names


def test_a_failed_run_leaves_no_folder(tmp_path, capsys, monkeypatch):
    """A run that fails while simulating (an internal error) removes everything it staged."""
    monkeypatch.chdir(tmp_path)
    from tether.silent.strategy import SilentStrategy

    def boom(self, ctx):
        raise RuntimeError("strategy exploded")

    monkeypatch.setattr(SilentStrategy, "step", boom)
    code, _, err = tether(capsys, "run", "silent_demo", "--out", "deep/inside/out")
    assert code == 1
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "internal error RuntimeError: strategy exploded" in lines[0]
    assert "TETHER_DEBUG=1" in lines[0]
    assert list(tmp_path.iterdir()) == []


def test_a_full_disk_is_one_line_and_leaves_nothing(tmp_path, capsys, monkeypatch):
    import errno

    from tether import runfolder

    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(runfolder, "write_table", full)
    data = silent(tmp_path)
    data["sim"]["max_steps"] = 3
    (tmp_path / "s.yaml").write_text(yaml.safe_dump(data))
    code, _, err = tether(capsys, "run", "s.yaml", "--out", "out/run", "--no-figures")
    assert_one_line(code, err, "out/run: cannot write the run folder (No space left on device)")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.yaml"]


def test_internal_error_keeps_exit_1_and_traceback_on_request(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    from tether.silent.strategy import SilentStrategy

    def boom(self, ctx):
        raise RuntimeError("strategy exploded")

    monkeypatch.setattr(SilentStrategy, "step", boom)
    monkeypatch.setenv("TETHER_DEBUG", "1")
    with pytest.raises(RuntimeError, match="strategy exploded"):
        cli.main(["run", "silent_demo", "--out", "out"])


# --------------------------------------------------------------------------- subprocesses


def _proc(*args: str, cwd: Path, env: dict[str, str] | None = None) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "tether.cli", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=120,
        env={**os.environ, **(env or {})},
    )


@pytest.mark.parametrize(
    "args",
    [(), ("fly",), ("run", "--seed", "abc"), ("validate", "bad.yaml")],
    ids=["no-args", "unknown-command", "seed-abc", "bad-file"],
)
def test_real_processes_print_one_line(tmp_path, args):
    (tmp_path / "bad.yaml").write_bytes(b"name: caf\xe9\n")
    proc = _proc(*args, cwd=tmp_path)
    assert proc.returncode == 2, proc.stderr
    assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
    assert proc.stderr.startswith("error: ")


def test_real_process_without_click_importable(tmp_path):
    """typer bundles click; tether must not need the `click` package (the README install)."""
    blocker = tmp_path / "block"
    blocker.mkdir()
    (blocker / "click.py").write_text("raise ImportError('click is not installed here')\n")
    env = {"PYTHONPATH": os.pathsep.join([str(blocker), os.environ.get("PYTHONPATH", "")])}
    typer_alone = subprocess.run(
        [sys.executable, "-c", "import typer"], capture_output=True, env={**os.environ, **env}
    )
    if typer_alone.returncode != 0:
        pytest.skip("this typer imports click itself (typer < 0.22 did)")
    for args in [(), ("run", "--bogus"), ("run", "--seed", "abc")]:
        proc = _proc(*args, cwd=tmp_path, env=env)
        assert proc.returncode == 2, proc.stderr
        assert len(proc.stderr.strip().splitlines()) == 1, proc.stderr
