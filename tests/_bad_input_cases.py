"""The corpus of bad scenario inputs of ``tests/test_bad_inputs.py``: bases and cases.

Each :class:`Case` is a valid base scenario with one change (or raw bytes); the test
writes it with :func:`write_case` and checks that ``validate``, ``run`` (and for sweep
cases ``sweep``) refuse it with the same one line naming ``Case.field``.
"""

from __future__ import annotations

import struct
import zlib
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml
from PIL import Image

from tether.config import load_scenario

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
            _set("sim.max_steps", 1),  # records that fit: the links are what cannot
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
    "map in 3-D without its height": Case(
        "world.params.height_m",
        _all(lambda d, t: d.update(world=wall_map(t)), _set("world.dim", 3)),
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


def write_case(case: Case, tmp: Path) -> Path:
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
