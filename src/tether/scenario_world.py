"""The world of a scenario: its scene's files found (or stood in for), the scene built.

A scene reads files named by ``world.params.path`` (a map, an obstacle point file) or
``world.params.file``. A relative path is looked up beside the scenario file, then from
the current folder (:meth:`tether.config.Scenario.resolve_path`). A scenario may name a
*stand-in* as ``world.params.stand_in_path``: a file used, with a
:class:`~tether.errors.TetherWarning`, when ``path`` is not found. The built-in
scenarios on the recurrent paper's maps use it: the maps beside a checkout of the
repository cannot be shipped, so a built-in name runs anywhere on a map of the same
kind that tether makes and ships (``tether/scenarios/maps``).

A run keeps the files its world read (:func:`keep_scene_files`): copied into the run
folder's ``files/`` (a ROS map YAML with its image), the run's ``scenario.yaml``
pointing at the copies, and ``summary.json`` recording each file's SHA-256, so
``tether run RUN_DIR/scenario.yaml`` runs the same world from any folder.
"""

from __future__ import annotations

import hashlib
import inspect
import re
import shutil
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from tether.config import Scenario
from tether.errors import MapError, ScenarioError, TetherError, TetherWarning
from tether.registry import SCENES
from tether.suggest import did_you_mean
from tether.world.scenes import make_scene
from tether.world.world import World
from tether.yamlfile import read_yaml

__all__ = [
    "FILE_KEYS",
    "MAX_KEPT_BYTES",
    "STAND_IN_KEY",
    "SceneFile",
    "build_world",
    "keep_scene_files",
    "scene_files",
]

#: ``world.params`` keys that name a file the scene reads
FILE_KEYS = ("path", "file")
#: ``world.params`` key of the file used when ``path`` is not found
STAND_IN_KEY = "stand_in_path"

#: a scene file larger than this is not copied into the run folder (its path and hash are
#: recorded instead): a sweep of hundreds of trials would copy it hundreds of times
MAX_KEPT_BYTES = 16 * 2**20
#: the run folder's subfolder holding the scene files
FILES_DIR = "files"

#: worlds of procedural scenes with a fixed layout seed (``world.params.seed``), per process
_WORLDS: dict[str, World] = {}
_WORLDS_KEPT = 4
#: (path given, stand-in) pairs already warned about in this process
_WARNED: set[tuple[str, str]] = set()


@dataclass(frozen=True)
class SceneFile:
    """A file the scene reads: its key, the path as given, and the file found.

    ``stand_in_for`` is the path the scenario gave when the file found is its stand-in.
    """

    key: str
    given: str
    path: Path
    stand_in_for: str | None = None


def _path_value(scenario: Scenario, key: str, value: Any) -> str:
    if not isinstance(value, str) or not value:
        raise ScenarioError(
            f"{scenario.source}: world.params.{key}: got {value!r}; it must be a file path "
            "string (e.g. ../shared/maps/grass.png)"
        )
    return value


def scene_files(scenario: Scenario) -> tuple[dict[str, Any], list[SceneFile]]:
    """The scene's parameters with its files resolved (absolute), and those files.

    ``stand_in_path`` is removed from the parameters; when ``path`` is not found and it
    is given (and found), ``path`` becomes the stand-in and a
    :class:`~tether.errors.TetherWarning` says so.

    Raises
    ------
    ScenarioError
        ``<file>: world.params.<key>: <path>: file not found ...`` (naming the stand-in
        too when neither is found).
    """
    src = scenario.source
    params = dict(scenario.world.params)
    stand_in = params.pop(STAND_IN_KEY, None)
    if stand_in is not None:
        _path_value(scenario, STAND_IN_KEY, stand_in)
        if "path" not in params:
            raise ScenarioError(
                f"{src}: world.params.{STAND_IN_KEY}: stands in for world.params.path, "
                "which is not given; give path or remove stand_in_path"
            )
    files = []
    for key in FILE_KEYS:
        if key not in params:
            continue
        given = _path_value(scenario, key, params[key])
        resolved, exists = _resolve(scenario, key, given)
        found = SceneFile(key, given, resolved)
        if not exists and key == "path" and stand_in is not None:
            other, other_exists = _resolve(scenario, STAND_IN_KEY, stand_in)
            if not other_exists:
                raise ScenarioError(
                    f"{src}: world.params.{STAND_IN_KEY}: {stand_in}: file not found beside "
                    f"the scenario ({scenario.base_dir}), and neither is world.params.path "
                    f"{given}; give a path to an existing file"
                )
            if (given, str(other)) not in _WARNED:  # once per process, not per trial
                _WARNED.add((given, str(other)))
                warnings.warn(
                    TetherWarning(
                        f"{src}: world.params.path: {given} not found; running on its stand-in "
                        f"{stand_in}, a map of the same kind that tether ships (results differ "
                        "from the original's)"
                    ),
                    stacklevel=3,
                )
            found = SceneFile(key, stand_in, other, stand_in_for=given)
        elif not exists:
            raise ScenarioError(
                f"{src}: world.params.{key}: {_shown(given)}: file not found beside the scenario "
                f"({scenario.base_dir}) or from the current directory; give a path "
                "relative to one of them or an absolute one"
            )
        params[key] = str(found.path)
        files.append(found)
    return params, files


def _shown(path: str, limit: int = 80) -> str:
    return path if len(path) <= limit else path[: limit - 3] + "..."


def _resolve(scenario: Scenario, key: str, given: str) -> tuple[Path, bool]:
    """The file's path and whether it exists; a path the file system cannot take (too
    long, a NUL byte) is one clear error."""
    try:
        resolved = scenario.resolve_path(given)
        return resolved, resolved.exists()
    except (OSError, ValueError) as exc:  # a name too long, a NUL byte
        reason = getattr(exc, "strerror", None) or "not a usable path"
        raise ScenarioError(
            f"{scenario.source}: world.params.{key}: {_shown(given)} is not a usable file path "
            f"({reason}); give a shorter path to the map or point file"
        ) from None


def _field_of(message: str, names: list[str], files: list[SceneFile]) -> str:
    """``<field>: <problem>`` of a scene's error: the parameter it is about as its field.

    Scenes that read a file name it first (``<file>: bounds_m: ...``); an error about
    another parameter than the file is reported under that parameter's own field, e.g.
    ``world.params.bounds_m: must be ... (reading <file>)``.
    """
    for name in names:
        found = re.search(rf"(^|: ){re.escape(name)}: ", message)
        if found and name not in FILE_KEYS:
            reading = f" (reading {files[0].given})" if files else ""
            return f"world.params.{name}: {message[found.end() :]}{reading}"
    return f"world.params.{files[0].key}: {message}" if files else f"world.params: {message}"


def build_world(scenario: Scenario, rng: np.random.Generator) -> World:
    """The scenario's world from the scene registry (``free``, ``map``, ``town``, ...).

    A scene whose layout is fixed by ``world.params.seed`` (and read from no file)
    is built once per process and shared by later runs with the same parameters:
    a campaign's worker then builds the town, its distance field and its obstacle
    index once, not per trial. Nothing in a run changes a world.
    """
    src, cfg = scenario.source, scenario.world
    if cfg.scene not in SCENES:
        raise ScenarioError(
            f"{src}: world.scene: unknown scene {cfg.scene!r}"
            f"{did_you_mean(cfg.scene, SCENES.names())}; expected one of: "
            f"{', '.join(SCENES.names())}"
        )
    params, files = scene_files(scenario)
    if cfg.scene in ("free", "map"):  # scenes whose dimension the scenario chooses
        params.setdefault("dim", cfg.dim)
    # a procedural layout fixed by its own seed is the same world for every run: keep it
    # (with its distance field and obstacle index) for the next runs of this process
    key = None
    if "seed" in params and not files:
        key = repr((cfg.scene, sorted(params.items())))
    world = _WORLDS.get(key) if key is not None else None
    if world is None:
        try:
            world = make_scene(cfg.scene, rng, **params)
        except (MapError, ScenarioError) as exc:
            names = [*inspect.signature(SCENES.get(cfg.scene)).parameters, *params]
            raise ScenarioError(f"{src}: {_field_of(str(exc), names, files)}") from None
        if key is not None:
            if len(_WORLDS) >= _WORLDS_KEPT:
                _WORLDS.pop(next(iter(_WORLDS)))
            _WORLDS[key] = world
    if world.dim != cfg.dim:
        raise ScenarioError(
            f"{src}: world.dim: scene {cfg.scene!r} is {world.dim}-D; set dim: {world.dim}"
        )
    return world


def _sha256(path: Path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(2**20), b""):
            digest.update(block)
    return digest.hexdigest()


def _map_image(path: Path) -> tuple[str, Path] | None:
    """``(image as written, image path)`` of a ROS map YAML, ``None`` for other files."""
    if path.suffix.lower() not in (".yaml", ".yml"):
        return None
    try:
        data = read_yaml(path, str(path))
    except (OSError, TetherError):
        return None
    image = data.get("image") if isinstance(data, dict) else None
    if not isinstance(image, str) or not image:
        return None
    found = Path(image).expanduser()
    return image, found if found.is_absolute() else path.parent / found


def keep_scene_files(
    staging: Path, data: dict[str, Any], files: list[SceneFile]
) -> list[dict[str, Any]]:
    """Copy the scene's files into ``staging / "files"`` and point ``data`` at the copies.

    Parameters
    ----------
    staging
        The run folder being written (its staging folder).
    data
        The scenario as it will be written to ``scenario.yaml`` (changed in place:
        ``world.params.<key>`` becomes ``files/<name>``, ``stand_in_path`` is dropped
        since the file used is the one kept).
    files
        The files the world read (:func:`scene_files`).

    Returns
    -------
    list of dict
        One record per file for ``summary.json``: ``key``, ``given`` (the path the
        scenario gave), ``stand_in`` (the stand-in used instead, or ``None``), ``used``
        (the absolute path read), ``sha256``, ``bytes`` and ``copy`` (the path in the run
        folder, or ``None`` for a file over :data:`MAX_KEPT_BYTES`, whose absolute path
        is then kept in ``scenario.yaml``).
    """
    params = data.setdefault("world", {}).setdefault("params", {})
    params.pop(STAND_IN_KEY, None)
    records = []
    taken: set[str] = set()
    for item in files:
        size = item.path.stat().st_size
        stood_in = item.stand_in_for is not None
        record: dict[str, Any] = {
            "key": f"world.params.{item.key}",
            "given": item.stand_in_for if stood_in else item.given,
            "stand_in": item.given if stood_in else None,
            "used": str(item.path.resolve()),
            "sha256": _sha256(item.path),
            "bytes": size,
            "copy": None,
        }
        image = _map_image(item.path)
        extra = image[1].stat().st_size if image and image[1].is_file() else 0
        if size + extra <= MAX_KEPT_BYTES:
            name = _free_name(item.path.name, taken)
            target = staging / FILES_DIR / name
            target.parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(item.path, target)
            if image is not None and image[1].is_file():
                image_name = _free_name(image[1].name, taken)
                shutil.copyfile(image[1], target.parent / image_name)
                if image_name != image[0]:  # the copy names the image beside it
                    map_data = read_yaml(item.path, str(item.path))
                    map_data["image"] = image_name
                    target.write_text(yaml.safe_dump(map_data, sort_keys=False))
            record["copy"] = f"{FILES_DIR}/{name}"
            params[item.key] = record["copy"]
        else:
            params[item.key] = str(item.path.resolve())
        records.append(record)
    return records


def _free_name(name: str, taken: set[str]) -> str:
    """``name``, or ``<stem>-2<suffix>`` ... if another kept file has it."""
    stem, suffix = Path(name).stem, Path(name).suffix
    candidate, k = name, 1
    while candidate in taken:
        k += 1
        candidate = f"{stem}-{k}{suffix}"
    taken.add(candidate)
    return candidate
