"""The sweep folder as a store that can be trusted after edits, kills and failures.

A sweep folder holds:

* ``sweep.yaml``: the scenario the sweep was made from (with its ``sweep:`` block);
* ``store.json``: the *scenario hash* (SHA-256 of the scenario without its
  ``sweep``, ``seed`` and ``output`` blocks, which do not change what one trial
  computes), the tether version and the store format;
* ``<combo>/seed-<s>/``: one run folder per finished trial, written atomically;
* ``sweep.parquet``: one row per trial (``status`` done or failed; ``seed``;
  ``error``; the ``param:`` values and the run's summary).

A rerun into a folder whose scenario hash differs is refused (the results of two
scenarios are never mixed); a rerun with more seeds or axis values adds trials.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Iterator
from contextlib import contextmanager, suppress
from pathlib import Path
from typing import Any

from tether import __version__
from tether.config import Scenario
from tether.errors import OutputError, TetherError
from tether.experiments.lock import LOCK_FILE, clean_leftovers, sweep_lock
from tether.runfolder import write_json, write_yaml
from tether.yamlfile import read_yaml

__all__ = [
    "STORE_FILE",
    "SWEEP_SCENARIO",
    "SWEEP_TABLE",
    "locked_store",
    "open_store",
    "scenario_hash",
]

#: the scenario of a sweep, written first into its folder (marks the folder as a sweep's)
SWEEP_SCENARIO = "sweep.yaml"
SWEEP_TABLE = "sweep.parquet"
STORE_FILE = "store.json"
STORE_FORMAT = 1
#: blocks of a scenario that do not change what one trial computes (left out of the hash)
UNHASHED = ("sweep", "seed", "output")


def _identity(data: dict[str, Any]) -> dict[str, Any]:
    return {k: v for k, v in data.items() if k not in UNHASHED}


def scenario_hash(data: dict[str, Any] | Scenario) -> str:
    """The hash of what a scenario's trials compute (16 hex digits of SHA-256).

    Parameters
    ----------
    data : dict or Scenario
        A scenario or its ``model_dump(mode="json")``.
    """
    if isinstance(data, Scenario):
        data = data.model_dump(mode="json")
    text = json.dumps(_identity(data), sort_keys=True, separators=(",", ":"), default=str)
    return hashlib.sha256(text.encode()).hexdigest()[:16]


def _flat(data: Any, prefix: str = "") -> dict[str, Any]:
    if isinstance(data, dict):
        out: dict[str, Any] = {}
        for key, value in data.items():
            out.update(_flat(value, f"{prefix}{key}."))
        return out
    return {prefix.rstrip("."): data}


def first_difference(old: dict[str, Any], new: dict[str, Any]) -> str:
    """The first key that differs between two scenarios, as ``key: old -> new``."""
    a, b = _flat(_identity(old)), _flat(_identity(new))
    for key in sorted(set(a) | set(b)):
        if a.get(key, "(absent)") != b.get(key, "(absent)"):
            before, after = repr(a.get(key, "(absent)")), repr(b.get(key, "(absent)"))
            return f"{key}: {before[:30]} -> {after[:30]}"
    return "a change"


def _recorded(out: Path) -> tuple[str | None, dict[str, Any] | None]:
    """The hash and scenario a sweep folder records (None when it records none)."""
    old: dict[str, Any] | None = None
    try:
        loaded = read_yaml(out / SWEEP_SCENARIO, str(out / SWEEP_SCENARIO))
        old = loaded if isinstance(loaded, dict) else None
    except (OSError, TetherError):
        pass
    try:
        recorded = json.loads((out / STORE_FILE).read_text()).get("scenario_hash")
    except (OSError, ValueError, AttributeError):
        recorded = None
    if recorded is None and old is not None:  # a folder from before store.json
        recorded = scenario_hash(old)
    return (str(recorded) if recorded is not None else None), old


def is_sweep_folder(out: Path) -> bool:
    """A folder a sweep wrote: it holds tether's ``store.json`` (never judged by common names).

    Only a regular file that is a JSON object of a store format this version reads, with
    the scenario hash and the tether version, counts.
    """
    file = out / STORE_FILE
    try:
        if file.is_symlink() or not file.is_file() or file.stat().st_size > 1 << 20:
            return False
        data = json.loads(file.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return False
    return (
        isinstance(data, dict)
        and data.get("format") == STORE_FORMAT
        and isinstance(data.get("scenario_hash"), str)
        and isinstance(data.get("tether_version"), str)
    )


def _check_folder(out: Path) -> bool:
    """Refuse a file or a foreign non-empty folder at ``out``; True if it is a sweep folder.

    A folder holding nothing but the sweep lock file counts as empty.
    """
    if out.is_symlink() or (out.exists() and not out.is_dir()):
        raise OutputError(f"{out}: exists and is not a folder; choose another --out")
    if not out.is_dir() or not any(p.name != LOCK_FILE for p in out.iterdir()):
        return False
    if not is_sweep_folder(out):
        raise OutputError(
            f"{out}: folder is not empty and not a tether sweep folder (it has no tether "
            f"{STORE_FILE}); choose a new or empty folder for --out (a sweep resumes only in "
            "its own folder)"
        )
    return True


@contextmanager
def locked_store(scenario: Scenario, out_dir: str | Path) -> Iterator[Path]:
    """:func:`open_store` under the folder's sweep lock, held for the ``with`` block.

    The folder is checked before anything is created in it; under the lock, what killed
    sweeps left (staging folders, temporary files) is removed first
    (:mod:`tether.experiments.lock`). A second sweep into the folder is refused in one line.
    """
    out = Path(out_dir)
    try:
        _check_folder(out)
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(
            f"{out}: cannot write the sweep folder ({exc.strerror or exc}); choose a writable --out"
        ) from None
    with sweep_lock(out):
        with suppress(OSError):  # what cannot be removed stays: it is hidden and never read
            clean_leftovers(out)
        yield open_store(scenario, out)


def open_store(scenario: Scenario, out_dir: str | Path) -> Path:
    """Create ``out_dir`` for a sweep of ``scenario``, or reopen the same scenario's sweep.

    Raises
    ------
    OutputError
        ``out_dir`` is a file; a non-empty folder that is not a sweep's (so ``--out .``
        never mixes a sweep into other files); the sweep of another scenario (its hash
        differs: the message names the first changed key and the fix, a new ``--out``);
        a place that cannot be created or written.
    """
    out = Path(out_dir)
    data = scenario.model_dump(mode="json")
    new_hash = scenario_hash(data)
    try:
        if _check_folder(out):
            old_hash, old = _recorded(out)
            if old_hash is not None and old_hash != new_hash:
                change = first_difference(old, data) if old is not None else "a change"
                raise OutputError(
                    f"{out}: holds the trials of another scenario (scenario hash {old_hash}, "
                    f"now {new_hash}; {change}); results are never mixed: give this scenario a "
                    "new --out, or undo the change to resume"
                )
        out.mkdir(parents=True, exist_ok=True)
        write_json(
            out / STORE_FILE,
            {
                "format": STORE_FORMAT,
                "scenario_hash": new_hash,
                "hash_covers": "the scenario without its " + ", ".join(UNHASHED) + " blocks",
                "tether_version": __version__,
            },
        )
        write_yaml(out / SWEEP_SCENARIO, data)
    except OSError as exc:
        raise OutputError(
            f"{out}: cannot write the sweep folder ({exc.strerror or exc}); choose a writable --out"
        ) from None
    return out
