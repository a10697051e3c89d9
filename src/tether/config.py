"""Scenario files: YAML validated by pydantic, with one-line errors.

A scenario names a world, a team, a sensor, the simulation clock and a
strategy (chosen from :data:`tether.registry.STRATEGIES` by name, its
``params`` validated by the strategy's own ``Params`` model). Every problem is
reported as a :class:`tether.errors.ScenarioError` whose message is one line:
``<file>: <field>: <what is expected>``.
"""

from __future__ import annotations

import math
from importlib import resources
from pathlib import Path
from typing import Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, model_validator

from tether.errors import ScenarioError

BUILTIN_PACKAGE = "tether.scenarios"


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", validate_assignment=True)


class WorldConfig(_Strict):
    """The workspace: a registered scene (``free``, ``map``, ``town``, ...) and its parameters."""

    scene: str = "free"
    dim: Literal[2, 3] = 2
    params: dict[str, Any] = Field(default_factory=dict)


class SensingConfig(_Strict):
    """Sensing model (see :mod:`tether.sensing`)."""

    range_m: float = Field(gt=0)
    body_radius_m: float = Field(default=0.0, ge=0)
    occlusion: bool = True
    radial_error_m: float = Field(default=0.0, ge=0)
    angular_error_deg: float = Field(default=0.0, ge=0, lt=90)
    noise: Literal["none", "uniform", "bound"] = "uniform"

    @model_validator(mode="after")
    def _radial_below_range(self) -> SensingConfig:
        if self.radial_error_m >= self.range_m:
            raise ValueError("radial_error_m must be smaller than range_m")
        return self

    @property
    def angular_error_rad(self) -> float:
        return math.radians(self.angular_error_deg)


class InitConfig(_Strict):
    """Initial team placement.

    ``random_connected``: robots added one by one, each within ``spacing_m`` of
    a random earlier robot (and at least ``min_separation_m`` from all), inside
    free space around ``center``. ``grid``: a square/cubic lattice of pitch
    ``spacing_m``. ``uniform``: uniformly at random in a box of side lengths
    ``extent_m`` around ``center``, redrawn until the sensing graph is connected
    and robots are ``min_separation_m`` apart. ``positions``: explicit ``(n, dim)`` list.
    """

    kind: Literal["random_connected", "uniform", "grid", "positions"] = "random_connected"
    spacing_m: float = Field(default=5.0, gt=0)
    min_separation_m: float = Field(default=1.0, ge=0)
    center: list[float] | None = None
    extent_m: list[float] | None = None
    positions: list[list[float]] | None = None


class TeamConfig(_Strict):
    n_robots: int = Field(gt=0)
    init: InitConfig = Field(default_factory=InitConfig)


class SimConfig(_Strict):
    dt_s: float = Field(default=1.0, gt=0)
    max_steps: int = Field(default=500, gt=0)
    collision_distance_m: float = Field(default=0.0, ge=0)


class OutputConfig(_Strict):
    dir: str = "runs"
    record_every: int = Field(default=1, gt=0)
    figures: bool = True


class StrategyConfig(_Strict):
    name: str
    params: dict[str, Any] = Field(default_factory=dict)


class Scenario(_Strict):
    """A complete, validated scenario."""

    name: str = "scenario"
    description: str = ""
    seed: int = 0
    world: WorldConfig = Field(default_factory=WorldConfig)
    team: TeamConfig
    sensing: SensingConfig
    sim: SimConfig = Field(default_factory=SimConfig)
    strategy: StrategyConfig
    output: OutputConfig = Field(default_factory=OutputConfig)
    sweep: dict[str, list[Any]] = Field(
        default_factory=dict,
        description="dotted scenario key -> values, run by `tether sweep` (grid of all values)",
    )

    # Where the scenario came from (for error messages and relative paths); not a YAML key.
    _source: str = "<scenario>"
    _base_dir: Path = Path(".")

    @property
    def source(self) -> str:
        return self._source

    @property
    def base_dir(self) -> Path:
        return self._base_dir

    def resolve_path(self, value: str | Path) -> Path:
        """A path from the scenario: relative to the scenario file's folder, else the cwd.

        The scenario's folder comes first (a scenario and its map travel together);
        a relative path that does not exist there is looked up from the current
        directory, so built-in scenarios can name data beside a checkout
        (``../shared/maps/grass.png`` run from the repository root).
        """
        p = Path(value).expanduser()
        if p.is_absolute():
            return p
        beside = self._base_dir / p
        if beside.exists() or not p.exists():
            return beside
        return p.resolve()


def _loc(loc: tuple[Any, ...]) -> str:
    return ".".join(str(p) for p in loc) or "(top level)"


def format_validation_error(source: str, err: ValidationError, prefix: str = "") -> str:
    """One line: ``file: field: message`` for the first error, plus a count of the rest."""
    errors = err.errors()
    first = errors[0]
    loc = _loc(tuple(first["loc"]))
    if prefix:
        loc = f"{prefix}.{loc}" if first["loc"] else prefix
    kind = first["type"]
    if kind == "extra_forbidden":
        msg = "unknown key; remove it or check its spelling"
    elif kind == "missing":
        msg = "required field is missing"
    else:
        msg = first["msg"]
        if "input" in first and not isinstance(first["input"], dict | list):
            msg += f" (got {first['input']!r})"
    more = f" (+{len(errors) - 1} more problem(s))" if len(errors) > 1 else ""
    return f"{source}: {loc}: {msg}{more}"


def builtin_scenarios() -> list[str]:
    """Names of the scenarios shipped with tether."""
    files = resources.files(BUILTIN_PACKAGE).iterdir()
    return sorted(f.name[:-5] for f in files if f.name.endswith(".yaml"))


def _read_yaml(path: Path, label: str) -> dict[str, Any]:
    try:
        text = path.read_text()
    except FileNotFoundError:
        names = ", ".join(builtin_scenarios())
        raise ScenarioError(
            f"{label}: file not found; give a scenario file or a built-in name ({names})"
        ) from None
    except OSError as exc:
        raise ScenarioError(f"{label}: cannot read file ({exc.strerror})") from None
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(exc, "problem", None) or "invalid YAML"
        raise ScenarioError(f"{label}: not valid YAML{where}: {problem}") from None
    if not isinstance(data, dict):
        raise ScenarioError(f"{label}: (top level): expected a mapping of scenario keys")
    return data


def scenario_from_dict(
    data: dict[str, Any], source: str = "<scenario>", base_dir: Path | None = None
) -> Scenario:
    """Validate a scenario given as a dict (e.g. built in Python)."""
    try:
        scenario = Scenario.model_validate(data)
    except ValidationError as exc:
        raise ScenarioError(format_validation_error(source, exc)) from None
    scenario._source = source
    scenario._base_dir = base_dir if base_dir is not None else Path(".")
    return scenario


def apply_overrides(data: dict[str, Any], overrides: list[str], source: str) -> dict[str, Any]:
    """Apply ``key.sub=value`` overrides (values parsed as YAML) to scenario data."""
    import copy

    data = copy.deepcopy(data)
    for item in overrides:
        key, sep, raw = item.partition("=")
        if not sep or not key:
            raise ScenarioError(f"--set {item!r}: expected KEY=VALUE, e.g. strategy.params.d0_m=5")
        set_dotted(data, key.strip(), yaml.safe_load(raw))
    return data


def set_dotted(data: dict[str, Any], key: str, value: Any) -> None:
    """Set ``data['a']['b'] = value`` for ``key = 'a.b'``, creating mappings as needed."""
    node = data
    parts = key.split(".")
    for part in parts[:-1]:
        child = node.get(part)
        if not isinstance(child, dict):
            child = {}
            node[part] = child
        node = child
    node[parts[-1]] = value


def read_scenario_data(path_or_name: str | Path) -> tuple[dict[str, Any], str, Path]:
    """Raw scenario data, its label for messages, and the folder relative paths refer to."""
    text = str(path_or_name)
    path = Path(text)
    bare_name = not text.endswith((".yaml", ".yml")) and "/" not in text
    if not path.exists() and bare_name and text in builtin_scenarios():
        ref = resources.files(BUILTIN_PACKAGE) / f"{text}.yaml"
        with resources.as_file(ref) as real:
            return _read_yaml(real, text), text, real.parent
    return _read_yaml(path, text), text, path.parent


def load_scenario(path_or_name: str | Path) -> Scenario:
    """Load and validate a scenario file, or a built-in scenario by name.

    Examples
    --------
    >>> s = load_scenario("silent_demo")
    >>> s.strategy.name
    'silent'
    """
    data, label, base = read_scenario_data(path_or_name)
    return scenario_from_dict(data, label, base)
