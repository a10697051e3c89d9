"""Scenario files: YAML validated by pydantic, with one-line errors.

A scenario names a world, a team, a sensor, the simulation clock and a
strategy (chosen from :data:`tether.registry.STRATEGIES` by name, its
``params`` validated by the strategy's own ``Params`` model). Every problem is
reported as a :class:`tether.errors.ScenarioError` whose message is one line:
``<file>: <field>: <what is expected>``.
"""

from __future__ import annotations

import hashlib
import math
import re
from importlib import resources
from pathlib import Path
from typing import Annotated, Any, Literal

from pydantic import (
    BaseModel,
    ConfigDict,
    Field,
    ValidationError,
    field_validator,
    model_validator,
)

from tether.errors import ScenarioError
from tether.suggest import did_you_mean, keys_at
from tether.sweepspec import MAX_SWEEP_COMBINATIONS as MAX_SWEEP_COMBINATIONS  # re-exported
from tether.sweepspec import MAX_SWEEP_TRIALS as MAX_SWEEP_TRIALS  # re-exported
from tether.sweepspec import SweepError, SweepSpec, parse_sweep
from tether.yamlfile import MAX_YAML_BYTES, read_yaml
from tether.yamlfile import MAX_YAML_VALUES as MAX_YAML_VALUES  # re-exported
from tether.yamlfile import YamlLoader as YamlLoader  # re-exported
from tether.yamlfile import parse_yaml as parse_yaml  # re-exported

BUILTIN_PACKAGE = "tether.scenarios"

#: the largest length or coordinate a scenario may give, in metres (10,000 km): far
#: beyond any robot team, small enough that squares and sums of lengths stay finite
MAX_LENGTH_M = 1e7
#: the longest a simulation step may be, in seconds (a day)
MAX_DT_S = 86_400.0
#: limits that keep a scenario bounded in time and memory before anything runs
MAX_ROBOTS = 1_000_000
MAX_STEPS = 100_000_000
MAX_SEED = 2**63 - 1
#: the longest scenario name, in bytes of UTF-8 (run folder names must stay under 255 bytes)
MAX_NAME_BYTES = 100
#: a run folder name part longer than this (bytes) is shortened and given a hash
MAX_LABEL_BYTES = 80
#: a scenario file larger than this is refused before it is parsed (every YAML file's limit)
MAX_SCENARIO_BYTES = MAX_YAML_BYTES

#: a coordinate in metres (finite, within +-MAX_LENGTH_M)
Coordinate = Annotated[float, Field(ge=-MAX_LENGTH_M, le=MAX_LENGTH_M, allow_inf_nan=False)]


def finite_strict(**extra: Any) -> ConfigDict:
    """The model config of every scenario model: unknown keys refused, floats finite."""
    return ConfigDict(extra="forbid", allow_inf_nan=False, **extra)


class _Strict(BaseModel):
    model_config = finite_strict(validate_assignment=True)


class WorldConfig(_Strict):
    """The workspace: a registered scene (``free``, ``map``, ``town``, ...) and its parameters."""

    scene: str = Field(default="free", description="registered scene name (`tether list`)")
    dim: Literal[2, 3] = Field(default=2, description="dimension of the workspace")
    params: dict[str, Any] = Field(
        default_factory=dict, description="the scene's parameters (see the scene tables)"
    )


class SensingConfig(_Strict):
    """Sensing model (see :mod:`tether.sensing`)."""

    range_m: float = Field(gt=0, le=MAX_LENGTH_M, description="sensing range d_max")
    body_radius_m: float = Field(
        default=0.0, ge=0, le=MAX_LENGTH_M, description="robot body radius (bodies occlude)"
    )
    occlusion: bool = Field(default=True, description="robot bodies hide the robots behind them")
    radial_error_m: float = Field(
        default=0.0, ge=0, le=MAX_LENGTH_M, description="bound on the measured distance's error"
    )
    angular_error_deg: float = Field(
        default=0.0, ge=0, lt=90, description="bound on the measured bearing's error"
    )
    noise: Literal["none", "uniform", "bound"] = Field(
        default="uniform",
        description="measurement errors: none, uniform within the bounds, or always at them",
    )

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
    and robots are ``min_separation_m`` apart (a box that cannot hold the team that far
    apart, or whose draws would list more than 50 M links, is refused before any draw).
    ``positions``: explicit ``(n, dim)`` list.
    """

    kind: Literal["random_connected", "uniform", "grid", "positions"] = Field(
        default="random_connected", description="how the team is placed"
    )
    spacing_m: float = Field(
        default=5.0, gt=0, le=MAX_LENGTH_M, description="random_connected: link length; grid: pitch"
    )
    min_separation_m: float = Field(
        default=1.0, ge=0, le=MAX_LENGTH_M, description="least distance between two robots"
    )
    center: list[Coordinate] | None = Field(
        default=None,
        description="centre of the placement (m; default: the world's centre, or the origin)",
    )
    extent_m: list[Annotated[float, Field(gt=0, le=MAX_LENGTH_M)]] | None = Field(
        default=None, description="uniform: side lengths of the box"
    )
    positions: list[list[Coordinate]] | None = Field(
        default=None, description="positions: one point (m) per robot"
    )


class TeamConfig(_Strict):
    """The team: how many robots and where they start."""

    n_robots: int = Field(gt=0, le=MAX_ROBOTS, description="number of robots")
    init: InitConfig = Field(default_factory=InitConfig, description="initial placement")


class SimConfig(_Strict):
    """The simulation clock."""

    dt_s: float = Field(default=1.0, gt=0, le=MAX_DT_S, description="time step (control period)")
    max_steps: int = Field(default=500, gt=0, le=MAX_STEPS, description="steps at most")
    collision_distance_m: float = Field(
        default=0.0, ge=0, le=MAX_LENGTH_M, description="robots closer than this collide"
    )


class OutputConfig(_Strict):
    """What a run writes."""

    dir: str = Field(default="runs", description="folder the run folder is made in")
    record_every: int = Field(
        default=1, gt=0, le=MAX_STEPS, description="keep positions and links every k-th step"
    )
    figures: bool = Field(default=True, description="draw the PNG figures")


class StrategyConfig(_Strict):
    """The strategy by name and its parameters."""

    name: str = Field(description="registered strategy name (`tether list`)")
    params: dict[str, Any] = Field(
        default_factory=dict, description="the strategy's parameters (see its table)"
    )


class Scenario(_Strict):
    """A complete, validated scenario."""

    name: str = Field(
        default="scenario", min_length=1, max_length=100, description="names the run folder"
    )
    description: str = Field(default="", description="free text for the reader")
    seed: int = Field(default=0, ge=0, le=MAX_SEED, description="seed of every random draw")
    world: WorldConfig = Field(default_factory=WorldConfig, description="the workspace")
    team: TeamConfig = Field(description="the robots")
    sensing: SensingConfig = Field(description="who senses whom")
    sim: SimConfig = Field(default_factory=SimConfig, description="the simulation clock")
    strategy: StrategyConfig = Field(description="the connectivity strategy")
    output: OutputConfig = Field(default_factory=OutputConfig, description="what a run writes")
    sweep: dict[str, Any] = Field(
        default_factory=dict,
        description="axes (dotted scenario key -> values or range), zip groups and seeds, run by "
        "`tether sweep` (grammar: tether.sweepspec)",
    )

    @field_validator("name")
    @classmethod
    def _name_is_a_file_name(cls, value: str) -> str:
        if any(c in value for c in "/\\\x00") or value in (".", ".."):
            raise ValueError(
                "must not contain '/' or '\\' (it names the run folder); use e.g. 'a-b'"
            )
        if not value.isprintable():
            raise ValueError("must be printable text on one line (it names the run folder)")
        size = len(value.encode("utf-8", "surrogatepass"))
        if size > MAX_NAME_BYTES:
            raise ValueError(
                f"must be at most {MAX_NAME_BYTES} bytes in UTF-8 (it names the run folder; "
                f"got {size} bytes); shorten it"
            )
        return value

    # Where the scenario came from (for error messages and relative paths); not a YAML key.
    _source: str = "<scenario>"
    _base_dir: Path = Path(".")

    @property
    def source(self) -> str:
        return self._source

    @property
    def base_dir(self) -> Path:
        return self._base_dir

    def with_seed(self, seed: int) -> Scenario:
        """This scenario with ``seed`` as its own: the seed a run, a trial or an episode ran.

        The seed draws everything random in a run, the strategy's own draws from
        ``scenario.seed`` included (e.g. the targets of ``multi_target``, whose
        configuration is the run seed); source and folder stay those of this scenario.
        """
        if seed == self.seed:
            return self
        out = self.model_copy(update={"seed": seed})
        out._source, out._base_dir = self._source, self._base_dir
        return out

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
        if _exists(beside) or not _exists(p):
            return beside
        return p.resolve()


def _exists(path: Path) -> bool:
    """``path.exists()``, False for a path the file system cannot take (a name too long, a
    NUL byte): the caller that needs the file says why in one line."""
    try:
        return path.exists()
    except (OSError, ValueError):
        return False


def _loc(loc: tuple[Any, ...]) -> str:
    return ".".join(str(p) for p in loc) or "(top level)"


def format_validation_error(
    source: str, err: ValidationError, prefix: str = "", model: type[BaseModel] | None = None
) -> str:
    """One line: ``file: field: message`` for the first error, plus a count of the rest.

    With the ``model`` that was validated, a misspelt key or choice names the closest
    valid one (``unknown key (did you mean 'gamma'?)``).
    """
    errors = err.errors()
    first = errors[0]
    loc = _loc(tuple(first["loc"]))
    if prefix:
        loc = f"{prefix}.{loc}" if first["loc"] else prefix
    kind = first["type"]
    if kind == "extra_forbidden":
        keys = keys_at(model, tuple(first["loc"])[:-1])
        hint = did_you_mean(str(first["loc"][-1]), keys) if first["loc"] else ""
        msg = f"unknown key{hint}; remove it or check its spelling"
    elif kind == "missing":
        msg = "required field is missing"
    else:
        msg = str(first["msg"]).removeprefix("Value error, ")
        if "input" in first and not isinstance(first["input"], dict | list):
            got = repr(first["input"])
            msg += f" (got {got if len(got) <= 60 else got[:57] + '...'})"
        expected = re.findall(r"'([^']*)'", str((first.get("ctx") or {}).get("expected", "")))
        if kind == "literal_error" and isinstance(first.get("input"), str):
            msg += did_you_mean(first["input"], expected)
    more = f" (+{len(errors) - 1} more problem(s))" if len(errors) > 1 else ""
    return " ".join(f"{source}: {loc}: {msg}{more}".split())


#: characters a run folder name keeps from a value (others become ``_``)
_NAME_CHARS = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789._+-")


def _label_part(key: str, value: Any) -> str:
    """``leaf=value`` in characters safe in a file name: a number whole, a text cleaned
    (and hashed if it had to be), a list or mapping as a short hash of its exact value."""
    leaf = key.rsplit(".", 1)[-1]
    digest = hashlib.sha1(repr(value).encode()).hexdigest()[:8]
    if isinstance(value, dict | list | tuple):
        return f"{leaf}=h{digest}"
    text = str(value)
    safe = re.sub(r"_+", "_", "".join(c if c in _NAME_CHARS else "_" for c in text))
    if safe == text and len(text.encode()) <= MAX_LABEL_BYTES and not text.startswith("."):
        return f"{leaf}={text}"
    return f"{leaf}={safe.strip('_.')[:40]}~{digest}"


def sweep_label(combo: dict[str, Any]) -> str:
    """The run-folder name of one sweep combination: ``d0_m=5.0,gamma=0.2`` (``base`` if none).

    Only letters, digits and ``._+-=,~`` appear: a list or mapping value (a waypoint
    list, a scene's parameters) is a short hash of its exact value (``params=h3fa2c1b0``),
    a text with other characters is cleaned and given a hash, so every combination keeps
    its own folder and no name needs quoting in a shell.
    """
    if not combo:
        return "base"
    parts = [_label_part(k, v) for k, v in combo.items()]
    label = ",".join(parts)
    if len(label.encode()) > 200:  # whole parts up to 100 bytes, then a hash of all
        kept = [p for k, p in enumerate(parts) if len(",".join(parts[: k + 1]).encode()) <= 100]
        label = f"{','.join(kept)}~{hashlib.sha1(label.encode()).hexdigest()[:10]}"
    return label


def builtin_scenarios() -> list[str]:
    """Names of the scenarios shipped with tether."""
    files = resources.files(BUILTIN_PACKAGE).iterdir()
    return sorted(f.name[:-5] for f in files if f.name.endswith(".yaml"))


def paper_campaigns() -> list[str]:
    """Names of the papers' campaigns shipped with tether: ``paper/<name>`` (sweep files)."""
    files = (resources.files(BUILTIN_PACKAGE) / "paper").iterdir()
    return sorted(f"paper/{f.name[:-5]}" for f in files if f.name.endswith(".yaml"))


def _read_yaml(path: Path, label: str) -> dict[str, Any]:
    try:
        data = read_yaml(path, label, what="a scenario file")
    except FileNotFoundError:
        names = ", ".join(builtin_scenarios())
        hint = did_you_mean(Path(str(label)).stem, [*builtin_scenarios(), *paper_campaigns()])
        if str(label).lower() in ("true", "false", "yes", "no", "0", "1"):
            hint = " (flags such as --no-figures take no value)"
        raise ScenarioError(
            f"{label}: file not found{hint}; give a scenario file or a built-in name ({names}, "
            "or a paper campaign: `tether list`)"
        ) from None
    except IsADirectoryError:
        raise ScenarioError(f"{label}: is a folder; give a scenario YAML file") from None
    except OSError as exc:
        raise ScenarioError(f"{label}: cannot read file ({exc.strerror or exc})") from None
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
        raise ScenarioError(format_validation_error(source, exc, model=Scenario)) from None
    scenario._source = source
    scenario._base_dir = base_dir if base_dir is not None else Path(".")
    sweep_spec(scenario)  # a malformed sweep block is refused with the scenario
    return scenario


def sweep_spec(scenario: Scenario) -> SweepSpec:
    """The parsed ``sweep:`` block of a scenario (:mod:`tether.sweepspec`).

    Raises
    ------
    ScenarioError
        ``<file>: sweep.<field>: <problem and fix>`` for a malformed block.
    """
    try:
        return parse_sweep(scenario.sweep)
    except SweepError as exc:
        raise ScenarioError(" ".join(f"{scenario.source}: {exc}".split())) from None


def apply_overrides(data: dict[str, Any], overrides: list[str], source: str) -> dict[str, Any]:
    """Apply ``key.sub=value`` overrides (values parsed as YAML) to scenario data."""
    import copy

    data = copy.deepcopy(data)
    for item in overrides:
        key, sep, raw = item.partition("=")
        key = key.strip()
        parts = key.split(".")
        if not sep or not key or not all(p.strip() for p in parts):
            raise ScenarioError(
                f"--set {item!r}: expected KEY=VALUE with a dotted KEY, e.g. strategy.params.d0_m=5"
            )
        try:
            value = parse_yaml(raw, f"--set {key}")
        except ScenarioError as exc:
            raise ScenarioError(f"{exc}; quote strings, e.g. --set '{key}=\"text\"'") from None
        set_dotted(data, key, value)
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
    try:
        exists = path.exists()
    except (OSError, ValueError) as exc:  # a name too long, a NUL byte
        raise ScenarioError(f"{text[:80]!r}: not a usable file name ({exc})") from None
    bare_name = not text.endswith((".yaml", ".yml")) and "/" not in text
    campaign = not exists and text.startswith("paper/") and text in paper_campaigns()
    if (not exists and bare_name and text in builtin_scenarios()) or campaign:
        ref = resources.files(BUILTIN_PACKAGE)
        for part in f"{text}.yaml".split("/"):
            ref = ref / part
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
