"""The grammar of a scenario's ``sweep:`` block: axes, ranges, zipped groups, seeds.

Two forms are accepted. The plain form maps dotted scenario keys to values; every
axis is crossed with every other::

    sweep:
      team.n_robots: [10, 15]
      strategy.params.d0_m: {start: 5, stop: 11, step: 3}   # 5, 8, 11

The full form puts the axes under ``axes`` and adds ``zip`` (groups of axes that move
together: equal lengths, value k of each axis in trial k) and ``seeds`` (a count,
counted from the scenario's ``seed``, or an explicit list)::

    sweep:
      axes:
        team.n_robots: {start: 10, stop: 35, step: 5}
        sensing.range_m: [10, 11, 12, 13, 14, 15]
        strategy.params.d0_m: [5.0, 8.0]
      zip: [[team.n_robots, sensing.range_m]]
      seeds: 20

An optional ``quick`` entry gives the experiment a *quick size* that runs in minutes
(``tether sweep FILE --quick``): fewer seeds, shorter axes, and scenario keys set for
the quick run only::

    sweep:
      axes: {team.n_robots: {start: 10, stop: 35, step: 5}}
      seeds: 100
      quick:
        seeds: 2                          # replaces sweep.seeds
        axes: {team.n_robots: [10, 35]}   # replaces these axes' values (axes of the sweep)
        set: {sim.max_steps: 600}         # scenario keys of the quick run (not axes)

A range ``{start, stop, step}`` or ``{start, stop, num}`` includes both ends when they
fall on the grid. Trials are always *paired*: seed ``s`` is run on every combination,
and since the run seed drives every random draw (initial team, scene, noise), one seed
gives the same random configuration on every axis that does not change what is drawn.

This module is pure data (no scenario validation): :func:`parse_sweep` turns the block
into a :class:`SweepSpec` or raises :class:`SweepError` naming the field and the fix.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
from dataclasses import dataclass
from typing import Any

#: a sweep grid holds at most this many combinations
MAX_SWEEP_COMBINATIONS = 10_000
MAX_SWEEP_TRIALS = 100_000  # combinations x seeds
MAX_COMBOS = MAX_SWEEP_COMBINATIONS
#: keys of the full form (everything else in a plain block is an axis)
RESERVED = ("axes", "zip", "seeds", "quick")
#: keys of the ``quick`` entry
QUICK_KEYS = ("seeds", "axes", "set")
_RANGE_KEYS = {"start", "stop", "step", "num"}


class SweepError(ValueError):
    """A malformed ``sweep:`` block: ``field`` (e.g. ``sweep.zip``) and a message with the fix."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(f"{field}: {message}")
        self.field = field
        self.message = message


@dataclass(frozen=True)
class QuickSpec:
    """The ``quick`` entry of a ``sweep:`` block: the experiment at a size that runs in minutes.

    Attributes
    ----------
    seeds : int or list of int or None
        Replaces the block's ``seeds`` (None: keep them).
    axes : dict of str to Any
        Axes of the sweep whose values the quick size replaces (as written: lists or ranges).
    set : dict of str to Any
        Dotted scenario keys (not axes) and their values for the quick size.
    """

    seeds: int | list[int] | None
    axes: dict[str, Any]
    set: dict[str, Any]


@dataclass(frozen=True)
class SweepSpec:
    """A parsed ``sweep:`` block.

    Attributes
    ----------
    axes : dict of str to list
        Every axis (dotted scenario key) with its values, ranges expanded, in file order.
    groups : list of tuple of str
        The axes in crossing order; the axes of one group are zipped (equal lengths).
    seeds : int or list of int or None
        A count of seeds, an explicit list, or None when the block names none.
    quick : QuickSpec or None
        The block's quick size, or None when it has none.
    """

    axes: dict[str, list[Any]]
    groups: list[tuple[str, ...]]
    seeds: int | list[int] | None = None
    quick: QuickSpec | None = None

    def group_rows(self, group: tuple[str, ...], axes: dict[str, list[Any]] | None = None) -> list:
        """The value rows of one group: ``[{axis: value, ...}, ...]`` (zipped)."""
        axes = self.axes if axes is None else axes
        n = len(axes[group[0]])
        return [{key: axes[key][k] for key in group} for k in range(n)]

    @property
    def n_combinations(self) -> int:
        """How many combinations the grid has (product over groups of their lengths)."""
        return math.prod(len(self.axes[g[0]]) for g in self.groups)

    def combinations(self, axes: dict[str, list[Any]] | None = None) -> list[dict[str, Any]]:
        """Every combination in a stable order (one empty dict if there are no axes).

        ``axes`` may replace the values (same keys and lengths), e.g. by their
        normalised forms.
        """
        rows = [self.group_rows(g, axes) for g in self.groups]
        out = []
        for parts in itertools.product(*rows):
            combo: dict[str, Any] = {}
            for part in parts:
                combo.update(part)
            out.append({key: combo[key] for key in self.axes})  # file order of the axes
        return out

    def followers(self) -> set[str]:
        """The axes of each zip group after its first, when the first alone tells the
        group's rows apart: names and legends show the first axis of such a group only."""
        out: set[str] = set()
        for group in self.groups:
            lead = [value_key(v) for v in self.axes[group[0]]]
            if len(group) > 1 and len(set(lead)) == len(lead):
                out.update(group[1:])
        return out

    def seed_list(self, base_seed: int, override: int | list[int] | None = None) -> list[int]:
        """The seeds to run: ``override`` (e.g. ``--seeds``), else the block's, else one."""
        seeds = override if override is not None else self.seeds
        if seeds is None:
            seeds = 1
        if isinstance(seeds, int):
            return [base_seed + k for k in range(seeds)]
        return list(seeds)


def _is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool) and math.isfinite(value)


def expand_range(field: str, spec: dict[str, Any]) -> list[Any]:
    """The values of a range ``{start, stop, step}`` or ``{start, stop, num}`` (ends included)."""
    unknown = sorted(set(spec) - _RANGE_KEYS)
    if unknown:
        raise SweepError(
            field, f"unknown range key {unknown[0]!r}; use start, stop and step or num"
        )
    if "start" not in spec or "stop" not in spec or ("step" in spec) == ("num" in spec):
        raise SweepError(
            field,
            "a range needs start, stop and one of step or num, e.g. {start: 10, stop: 35, step: 5}",
        )
    start, stop = spec["start"], spec["stop"]
    if not (_is_number(start) and _is_number(stop)):
        raise SweepError(field, f"start and stop must be finite numbers (got {start!r}, {stop!r})")
    if stop < start:
        raise SweepError(field, f"stop {stop!r} is below start {start!r}; swap them")
    if "num" in spec:
        num = spec["num"]
        if (
            not isinstance(num, int)
            or isinstance(num, bool)
            or not 1 <= num <= MAX_SWEEP_COMBINATIONS
        ):
            raise SweepError(
                field, f"num must be an integer in 1..{MAX_SWEEP_COMBINATIONS:,} (got {num!r})"
            )
        if num == 1:
            return [start]
        width = (stop - start) / (num - 1)
        return [_tidy(start + k * width) for k in range(num)]
    step = spec["step"]
    if not _is_number(step) or step <= 0:
        raise SweepError(field, f"step must be a number > 0 (got {step!r})")
    n = math.floor((stop - start) / step * (1 + 1e-12) + 1e-9) + 1
    if n > MAX_SWEEP_COMBINATIONS:
        raise SweepError(
            field,
            f"the range has {n:,} values; at most {MAX_SWEEP_COMBINATIONS:,} (use a larger step)",
        )
    if all(isinstance(v, int) for v in (start, stop, step)):
        return [start + k * step for k in range(n)]
    return [_tidy(start + k * step) for k in range(n)]


def _tidy(value: float) -> float:
    """``0.30000000000000004`` -> ``0.3``: a float rounded to 12 significant digits."""
    return float(f"{value:.12g}")


def _axis_values(field: str, raw: Any) -> list[Any]:
    if isinstance(raw, dict):
        values = expand_range(field, raw)
    elif isinstance(raw, list):
        values = raw
    else:
        raise SweepError(
            field,
            f"an axis is a list of values or a range {{start, stop, step}} "
            f"(got {type(raw).__name__} {raw!r:.40})",
        )
    if not values:
        raise SweepError(field, "empty axis; give at least one value or remove the axis")
    return values


def _parse_seeds(seeds: Any, field: str = "sweep.seeds") -> int | list[int]:
    if isinstance(seeds, int) and not isinstance(seeds, bool):
        if seeds < 1:
            raise SweepError(field, f"a count of seeds must be >= 1 (got {seeds})")
        return seeds
    if isinstance(seeds, list) and seeds:
        bad = [s for s in seeds if not isinstance(s, int) or isinstance(s, bool) or s < 0]
        if bad:
            raise SweepError(field, f"seeds are integers >= 0 (got {bad[0]!r})")
        if len(set(seeds)) != len(seeds):
            raise SweepError(field, "a seed is listed twice; list each seed once")
        return list(seeds)
    raise SweepError(field, f"give a count (e.g. 20) or a non-empty list of seeds (got {seeds!r})")


def parse_sweep(block: dict[str, Any]) -> SweepSpec:
    """Parse a ``sweep:`` block (plain or full form) into a :class:`SweepSpec`.

    Raises
    ------
    SweepError
        For an empty or non-list axis, a bad range, a ``zip`` group naming an unknown
        axis, an axis in two groups, zipped axes of unequal lengths, bad seeds.
    """
    if not isinstance(block, dict):
        raise SweepError("sweep", "must be a mapping of axes, e.g. {team.n_robots: [10, 15]}")
    if "axes" in block:
        extra = sorted(set(block) - set(RESERVED))
        if extra:
            raise SweepError(
                f"sweep.{extra[0]}",
                "unknown key beside 'axes'; put axes under 'axes' "
                "(allowed here: axes, zip, seeds, quick)",
            )
        raw_axes = block["axes"]
        if not isinstance(raw_axes, dict) or not raw_axes:
            raise SweepError(
                "sweep.axes", "must map dotted keys to values, e.g. {team.n_robots: [10, 15]}"
            )
    else:
        raw_axes = {k: v for k, v in block.items() if k not in RESERVED}
    axes: dict[str, list[Any]] = {}
    for key, raw in raw_axes.items():
        if not isinstance(key, str) or not key or not all(key.split(".")):
            raise SweepError(f"sweep.{key}", "an axis is a dotted scenario key, e.g. team.n_robots")
        axes[key] = _axis_values(f"sweep.{key}", raw)
    groups = _groups(axes, block.get("zip", []))
    seeds = _parse_seeds(block["seeds"]) if "seeds" in block else None
    quick = _parse_quick(block["quick"], axes, block.get("zip", [])) if "quick" in block else None
    spec = SweepSpec(axes, groups, seeds, quick)
    _check_size("sweep", spec)
    return spec


def _check_size(field: str, spec: SweepSpec) -> None:
    if spec.n_combinations > MAX_SWEEP_COMBINATIONS:
        raise SweepError(
            field,
            f"the grid has {spec.n_combinations:,} combinations; at most "
            f"{MAX_SWEEP_COMBINATIONS:,} (sweep fewer values, or split the sweep)",
        )
    seeds = spec.seeds if isinstance(spec.seeds, int) else len(spec.seeds or [1])
    if spec.n_combinations * seeds > MAX_SWEEP_TRIALS:
        raise SweepError(
            f"{field}.seeds",
            f"{spec.n_combinations:,} combinations x {seeds:,} seeds = "
            f"{spec.n_combinations * seeds:,} trials; at most {MAX_SWEEP_TRIALS:,} "
            "(use fewer seeds or values)",
        )


def _parse_quick(raw: Any, axes: dict[str, list[Any]], zipped: Any) -> QuickSpec:
    """Parse the ``quick`` entry against the sweep's axes and zip groups."""
    field = "sweep.quick"
    if not isinstance(raw, dict) or not raw:
        raise SweepError(
            field,
            "a mapping of seeds, axes and set, e.g. {seeds: 2, set: {sim.max_steps: 600}}",
        )
    unknown = sorted(set(map(str, raw)) - set(QUICK_KEYS))
    if unknown:
        raise SweepError(f"{field}.{unknown[0]}", "unknown key; allowed: seeds, axes, set")
    seeds = _parse_seeds(raw["seeds"], f"{field}.seeds") if "seeds" in raw else None
    quick_axes = raw.get("axes", {})
    if not isinstance(quick_axes, dict):
        raise SweepError(
            f"{field}.axes", "map axes of the sweep to values, e.g. {team.n_robots: [10]}"
        )
    values = dict(axes)
    for key, value in quick_axes.items():
        if key not in axes:
            raise SweepError(
                f"{field}.axes.{key}",
                f"not an axis of the sweep (axes: {', '.join(axes) or 'none'}); the quick size "
                "only shortens axes: fix other keys under quick.set",
            )
        values[key] = _axis_values(f"{field}.axes.{key}", value)
    settings = raw.get("set", {})
    if not isinstance(settings, dict):
        raise SweepError(
            f"{field}.set", "map dotted scenario keys to values, e.g. {sim.max_steps: 600}"
        )
    for key in settings:
        if not isinstance(key, str) or not key or not all(key.split(".")):
            raise SweepError(f"{field}.set.{key}", "a dotted scenario key, e.g. sim.max_steps")
        if key in axes:
            raise SweepError(
                f"{field}.set.{key}",
                "is an axis of the sweep; give its quick values under quick.axes",
            )
        if key == "sweep" or key.startswith("sweep."):
            raise SweepError(f"{field}.set.{key}", "the quick size cannot set the sweep block")
    quick_spec = SweepSpec(values, _groups(values, zipped, f"{field}.axes"), seeds)
    _check_size(field, quick_spec)
    return QuickSpec(seeds, dict(quick_axes), dict(settings))


def quick_block(block: dict[str, Any]) -> dict[str, Any]:
    """The ``sweep:`` block of the quick size (full form, no ``quick`` entry).

    The quick axes replace the sweep's, ``zip`` is kept and the quick ``seeds`` replace
    the block's. The quick ``set`` is not part of the block: it changes the scenario
    (see :func:`tether.quicksize.quick_data`).

    Raises
    ------
    SweepError
        The block is malformed or has no ``quick`` entry.
    """
    spec = parse_sweep(block)
    if spec.quick is None:
        raise SweepError(
            "sweep.quick",
            "the scenario has no quick size; add a quick entry to its sweep block "
            "(docs/how-to/experiments.md, 'The quick size') or run it without --quick",
        )
    raw_axes = block["axes"] if "axes" in block else {
        k: v for k, v in block.items() if k not in RESERVED
    }  # fmt: skip
    axes = {**raw_axes, **spec.quick.axes}
    out: dict[str, Any] = {"axes": axes} if axes else {}
    if block.get("zip"):
        out["zip"] = block["zip"]
    seeds = spec.quick.seeds if spec.quick.seeds is not None else block.get("seeds")
    if seeds is not None:
        out["seeds"] = seeds
    return out


def _groups(
    axes: dict[str, list[Any]], zipped: Any, field: str = "sweep.zip"
) -> list[tuple[str, ...]]:
    if not isinstance(zipped, list) or not all(isinstance(g, list) for g in zipped):
        raise SweepError(field, "a list of groups of axes, e.g. [[team.n_robots, sensing.range_m]]")
    group_of: dict[str, tuple[str, ...]] = {}
    for group in zipped:
        if len(group) < 2:
            raise SweepError(field, f"group {group!r} zips fewer than two axes; list two or more")
        for key in group:
            if not isinstance(key, str):  # a list or a mapping cannot name an axis
                shown = repr(key) if len(repr(key)) <= 60 else repr(key)[:57] + "..."
                raise SweepError(
                    field, f"{shown} is not an axis name; a group lists axes by their keys, "
                    "e.g. [team.n_robots, sensing.range_m]",
                )  # fmt: skip
            if key not in axes:
                raise SweepError(
                    field, f"{key!r} is not an axis of the sweep; axes: {', '.join(map(str, axes))}"
                )
            if key in group_of:
                raise SweepError(field, f"axis {key!r} is in two zip groups; put it in one")
        lengths = {key: len(axes[key]) for key in group}
        if len(set(lengths.values())) > 1:
            shown = ", ".join(f"{k} has {n}" for k, n in lengths.items())
            raise SweepError(
                field,
                f"zipped axes need equal lengths ({shown} values); "
                "give each axis of the group as many values",
            )
        for key in group:
            group_of[key] = tuple(group)
    groups: list[tuple[str, ...]] = []
    for key in axes:  # a group takes the place of its first axis
        group = group_of.get(key, (key,))
        if group not in groups:
            groups.append(group)
    return groups


def canonical(value: Any) -> Any:
    """A value in the form trial ids are made of: ``"15.0"`` -> ``15``, ``15.0`` -> ``15``.

    Strings that read as numbers become numbers and integral floats become integers,
    recursively in lists and mappings, so values that validate to the same scenario get
    the same id.
    """
    if isinstance(value, str):
        try:
            number = float(value.strip())
        except ValueError:
            return value
        return canonical(number) if math.isfinite(number) else value
    if isinstance(value, float) and math.isfinite(value) and value.is_integer():
        return int(value)
    if isinstance(value, list | tuple):
        return [canonical(v) for v in value]
    if isinstance(value, dict):
        return {str(k): canonical(v) for k, v in value.items()}
    return value


def value_key(value: Any) -> str:
    """The canonical text of a value (what its part of a trial id's hash is made of)."""
    return json.dumps(canonical(value), sort_keys=True, separators=(",", ":"), default=str)


def combo_hash(combo: dict[str, Any], length: int = 8) -> str:
    """A short hash of a combination's canonical keys and values (stable across runs)."""
    text = json.dumps({k: value_key(v) for k, v in combo.items()}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()[:length]
