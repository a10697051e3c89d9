"""Map files: PNG/PGM occupancy images and ROS map_server YAML.

Conventions (those of ROS ``map_server``):

* Image row 0 is the **top** of the map (largest y), column 0 its left edge
  (smallest x). Rows are flipped and the array transposed so that the result
  follows :class:`~tether.world.grid.OccupancyGrid`'s ``occupied[ix, iy]``.
* A pixel of value ``v`` in an image of maximum value ``M`` (255 for 8-bit,
  65535 for 16-bit images) has occupancy probability ``p = (M - v) / M``, or
  ``p = v / M`` if ``negate``. Colour pixels use the mean of their colour
  channels; an alpha channel is ignored.
* ``p > occupied_thresh`` is occupied, ``p < free_thresh`` is free, anything in
  between is *unknown*. :func:`load_map` counts unknown cells as occupied (a
  robot must not drive into them); :func:`load_map_layers` returns the two
  masks separately.
* The YAML's ``origin`` is the world position of the lower-left corner of the
  map (the corner of cell ``(0, 0)``).

Every problem with a file is raised as :class:`~tether.errors.MapError` with a
single line naming the file, the field and the fix.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from tether.atomic import atomic_write
from tether.config import MAX_LENGTH_M
from tether.errors import MapError
from tether.world.grid import OccupancyGrid
from tether.world.images import read_image
from tether.yamlfile import read_yaml

__all__ = [
    "MapLayers",
    "load_map",
    "load_map_layers",
    "read_image",
    "save_map",
]

MODES = ("trinary", "scale", "raw")
_YAML_SUFFIXES = (".yaml", ".yml")


@dataclass(eq=False)
class MapLayers:
    """A loaded map, with the unknown cells kept apart.

    Attributes
    ----------
    grid
        The occupancy grid a robot world uses: occupied **or unknown** cells
        are occupied.
    occupied
        Boolean ``(nx, ny)``: cells classified occupied.
    unknown
        Boolean ``(nx, ny)``: cells between the two thresholds (or, in raw
        mode, with a value above 100).
    meta
        Where the map came from: ``source``, ``image``, ``mode``, thresholds.
    """

    grid: OccupancyGrid
    occupied: np.ndarray
    unknown: np.ndarray
    meta: dict[str, Any] = field(default_factory=dict)


# --------------------------------------------------------------------------- errors


# --------------------------------------------------------------------------- images


def _classify(
    values: np.ndarray,
    maxval: int,
    *,
    mode: str,
    occupied_thresh: float,
    free_thresh: float,
    negate: bool,
) -> tuple[np.ndarray, np.ndarray]:
    """Occupied and unknown masks in image layout, as ROS map_server does."""
    if mode == "raw":
        # Raw mode: the value is the occupancy in percent; >100 means unknown.
        # ROS ignores ``negate`` here; we still apply the thresholds so that the
        # boolean grid means the same thing in every mode.
        unknown_raw = values > 100
        p = np.clip(values, 0, 100) / 100.0
    else:
        unknown_raw = np.zeros(values.shape, dtype=bool)
        p = values / maxval if negate else (maxval - values) / maxval
    occupied = (p > occupied_thresh) & ~unknown_raw
    free = (p < free_thresh) & ~unknown_raw
    return occupied, ~occupied & ~free


def _to_grid_layout(mask: np.ndarray) -> np.ndarray:
    """Image layout ``[row, col]`` (row 0 = top) -> grid layout ``[ix, iy]``."""
    return np.ascontiguousarray(mask[::-1].T)


# --------------------------------------------------------------------------- YAML fields


def _number(source: Path, name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise MapError.at(source, name, f"must be a number (got {value!r})")
    return float(value)


def _positive(source: Path, name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
        raise MapError.at(source, name, f"must be a positive number (got {value!r})")
    if not math.isfinite(value):
        raise MapError.at(source, name, f"must be a positive number (got {value!r})")
    return float(value)


def _fraction(source: Path, name: str, value: Any) -> float:
    number = _number(source, name, value)
    if not 0.0 <= number <= 1.0:
        raise MapError.at(source, name, f"must be a number between 0 and 1 (got {value!r})")
    return number


def _flag(source: Path, name: str, value: Any) -> bool:
    if isinstance(value, bool):
        return value
    if isinstance(value, int) and value in (0, 1):
        return bool(value)
    raise MapError.at(source, name, f"must be 0/1 or true/false (got {value!r})")


def _origin(source: Path, name: str, value: Any) -> np.ndarray:
    if value is None:
        return np.zeros(2)
    values = np.asarray(value).tolist() if isinstance(value, np.ndarray) else value
    if not isinstance(values, (list, tuple)) or len(values) not in (2, 3):
        raise MapError.at(source, name, f"must be a list [x, y, yaw] of numbers (got {value!r})")
    numbers = [_number(source, name, v) for v in values]
    if max(abs(v) for v in numbers[:2]) > MAX_LENGTH_M:
        raise MapError.at(
            source, name, f"must be within +-{MAX_LENGTH_M:g} m (got {numbers[:2]!r})"
        )
    if len(numbers) == 3 and numbers[2] != 0.0:
        raise MapError.at(
            source,
            name,
            f"yaw must be 0: rotated maps are not supported (got {numbers[2]!r}); "
            "rotate the image instead",
        )
    return np.asarray(numbers[:2])


def _thresholds(source: Path, occupied: Any, free: Any) -> tuple[float, float]:
    occ = _fraction(source, "occupied_thresh", occupied)
    fre = _fraction(source, "free_thresh", free)
    if not fre <= occ:
        raise MapError.at(
            source, "free_thresh", f"must not exceed occupied_thresh (got {fre!r} > {occ!r})"
        )
    return occ, fre


def _read_yaml(path: Path) -> dict[str, Any]:
    try:
        doc = read_yaml(path, str(path), MapError, what="a map YAML file")
    except OSError as exc:
        raise MapError.at(path, None, f"cannot read file ({exc.strerror or exc})") from None
    except MapError as exc:
        if "not UTF-8" in str(exc):
            raise MapError.at(
                path, None, "not a text YAML file (is it an image? use the .png/.pgm)"
            ) from None
        raise
    if not isinstance(doc, dict):
        raise MapError.at(
            path,
            None,
            "must be a mapping with ROS map_server keys (image, resolution, origin, ...)",
        )
    for key in ("image", "resolution"):
        if key not in doc:
            raise MapError.at(
                path, key, "required key missing (see ROS map_server's map YAML format)"
            )
    return doc


# --------------------------------------------------------------------------- loading


def load_map_layers(
    path: str | Path,
    *,
    resolution_m: float | None = None,
    origin_m: Any = None,
    occupied_thresh: float = 0.65,
    free_thresh: float = 0.196,
    negate: bool = False,
) -> MapLayers:
    """Load a map file and keep occupied and unknown cells apart.

    See :func:`load_map` for the parameters.
    """
    path = Path(path)
    if not path.is_file():
        raise MapError.at(path, None, "file not found")
    if path.suffix.lower() in _YAML_SUFFIXES:
        return _load_yaml(
            path,
            resolution_m=resolution_m,
            origin_m=origin_m,
            occupied_thresh=occupied_thresh,
            free_thresh=free_thresh,
            negate=negate,
        )
    resolution = 1.0 if resolution_m is None else _positive(path, "resolution_m", resolution_m)
    origin = _origin(path, "origin_m", origin_m)
    occ_th, free_th = _thresholds(path, occupied_thresh, free_thresh)
    values, maxval = read_image(path)
    meta = {"source": str(path), "image": str(path), "mode": "trinary"}
    meta["resolution_key"] = "resolution_m"  # where the resolution came from
    return _layers(
        values, maxval, resolution, origin, "trinary", occ_th, free_th, bool(negate), meta
    )


def _load_yaml(
    path: Path,
    *,
    resolution_m: float | None,
    origin_m: Any,
    occupied_thresh: float,
    free_thresh: float,
    negate: bool,
) -> MapLayers:
    doc = _read_yaml(path)
    image_name = doc["image"]
    if not isinstance(image_name, str) or not image_name.strip():
        raise MapError.at(
            path, "image", f"must be a file name such as map.pgm (got {image_name!r})"
        )
    image = Path(image_name)
    if not image.is_absolute():
        image = path.parent / image
    if not image.is_file():
        raise MapError.at(path, "image", f"file {image_name!r} not found next to the YAML")
    resolution = _positive(path, "resolution", doc["resolution"])
    if resolution_m is not None:
        resolution = _positive(path, "resolution_m", resolution_m)
    origin = _origin(path, "origin", doc.get("origin"))
    if origin_m is not None:
        origin = _origin(path, "origin_m", origin_m)
    occ_th, free_th = _thresholds(
        path, doc.get("occupied_thresh", occupied_thresh), doc.get("free_thresh", free_thresh)
    )
    neg = _flag(path, "negate", doc.get("negate", negate))
    mode = doc.get("mode", "trinary")
    if mode not in MODES:
        raise MapError.at(path, "mode", f"must be one of {', '.join(MODES)} (got {mode!r})")
    try:
        values, maxval = read_image(image)
    except MapError as exc:
        reason = str(exc).split(": ", 1)[-1]
        raise MapError.at(path, "image", f"{image_name!r}: {reason}") from None
    meta = {"source": str(path), "image": str(image), "mode": mode}
    meta["resolution_key"] = "resolution" if resolution_m is None else "resolution_m"
    return _layers(values, maxval, resolution, origin, mode, occ_th, free_th, neg, meta)


def _layers(
    values: np.ndarray,
    maxval: int,
    resolution: float,
    origin: np.ndarray,
    mode: str,
    occ_th: float,
    free_th: float,
    negate: bool,
    meta: dict[str, Any],
) -> MapLayers:
    occupied, unknown = _classify(
        values, maxval, mode=mode, occupied_thresh=occ_th, free_thresh=free_th, negate=negate
    )
    occupied = _to_grid_layout(occupied)
    unknown = _to_grid_layout(unknown)
    width_m = resolution * max(occupied.shape)
    key = meta.pop("resolution_key")  # the YAML's resolution, or the scenario's
    if width_m > MAX_LENGTH_M:
        raise MapError.at(
            meta["source"], key,
            f"{resolution:g} m per cell makes the map {width_m:.3g} m wide, more than "
            f"{MAX_LENGTH_M:g} m; give a resolution in metres per cell, e.g. 0.05",
        )  # fmt: skip
    grid = OccupancyGrid(occupied | unknown, resolution, origin)
    meta.update(occupied_thresh=occ_th, free_thresh=free_th, negate=negate)
    return MapLayers(grid=grid, occupied=occupied, unknown=unknown, meta=meta)


def load_map(
    path: str | Path,
    *,
    resolution_m: float | None = None,
    origin_m: Any = None,
    occupied_thresh: float = 0.65,
    free_thresh: float = 0.196,
    negate: bool = False,
) -> OccupancyGrid:
    """Load a 2-D occupancy grid from an image or a ROS map_server YAML.

    Parameters
    ----------
    path
        A PNG/PGM image (any image Pillow reads works too), or a ``.yaml`` /
        ``.yml`` file in ROS map_server format (keys ``image`` -- relative to
        the YAML's folder --, ``resolution``, ``origin: [x, y, yaw]`` with
        ``yaw`` 0, optional ``occupied_thresh``, ``free_thresh``, ``negate``,
        ``mode`` in trinary/scale/raw; other keys are ignored).
    resolution_m
        Metres per pixel. Defaults to the YAML's ``resolution``, or 1.0 for a
        bare image (one cell per pixel, as in the recurrent-connectivity
        paper). Given explicitly, it overrides the YAML.
    origin_m
        World position ``(x, y)`` of the map's lower-left corner; overrides
        the YAML's ``origin``. Default ``(0, 0)`` for a bare image.
    occupied_thresh, free_thresh, negate
        Classification of pixels (see the module docstring). For a YAML these
        are defaults used only when the YAML does not set them.

    Returns
    -------
    OccupancyGrid
        ``occupied[ix, iy]``; unknown cells count as occupied (use
        :func:`load_map_layers` to tell them apart).

    Raises
    ------
    MapError
        One line naming the file, the field and the fix.

    Notes
    -----
    Modes: *trinary* and *scale* both threshold ``p`` (for a boolean grid,
    scale's in-between probabilities are unknown); *raw* reads the pixel
    value as the occupancy in percent (``> 100`` unknown) and then applies
    the thresholds to ``value / 100``; ``negate`` is ignored in raw mode, as in
    ROS.
    """
    return load_map_layers(
        path,
        resolution_m=resolution_m,
        origin_m=origin_m,
        occupied_thresh=occupied_thresh,
        free_thresh=free_thresh,
        negate=negate,
    ).grid


# --------------------------------------------------------------------------- saving


def save_map(
    grid: OccupancyGrid,
    path_yaml: str | Path,
    *,
    unknown: np.ndarray | None = None,
) -> Path:
    """Write a 2-D grid as a ROS map_server pair: ``<name>.pgm`` + ``<name>.yaml``.

    Pixels are 0 (occupied), 254 (free) and 205 (unknown), as ROS
    ``map_saver`` writes them, with ``occupied_thresh: 0.65`` and
    ``free_thresh: 0.196``, so :func:`load_map` reads back the same grid,
    resolution and origin.

    Parameters
    ----------
    grid
        A 2-D occupancy grid.
    path_yaml
        Where to write the YAML; the image goes next to it with suffix ``.pgm``.
    unknown
        Optional boolean mask (grid layout) of cells to write as unknown.

    Returns
    -------
    Path
        The YAML file written.
    """
    path_yaml = Path(path_yaml)
    if grid.dim != 2:
        raise MapError.at(
            path_yaml, None, f"only 2-D grids can be saved as an image map (got {grid.dim}-D)"
        )
    if unknown is not None:
        unknown = np.asarray(unknown, dtype=bool)
        if unknown.shape != grid.shape:
            raise ValueError(f"unknown mask shape {unknown.shape} != grid shape {grid.shape}")
    pixels = np.where(grid.occupied, 0, 254).astype(np.uint8)
    if unknown is not None:
        pixels[unknown & ~grid.occupied] = 205
    image = pixels.T[::-1]  # grid [ix, iy] -> image [row, col], row 0 = top
    rows, cols = image.shape
    path_image = path_yaml.with_suffix(".pgm")
    path_yaml.parent.mkdir(parents=True, exist_ok=True)
    header = f"P5\n# written by tether\n{cols} {rows}\n255\n".encode("ascii")
    body = np.ascontiguousarray(image).tobytes()
    atomic_write(path_image, lambda tmp: Path(tmp).write_bytes(header + body))
    doc = {
        "image": path_image.name,
        "mode": "trinary",
        "resolution": float(grid.resolution_m),
        "origin": [float(grid.origin_m[0]), float(grid.origin_m[1]), 0.0],
        "negate": 0,
        "occupied_thresh": 0.65,
        "free_thresh": 0.196,
    }
    text = yaml.safe_dump(doc, sort_keys=False)
    atomic_write(path_yaml, lambda tmp: Path(tmp).write_text(text, encoding="utf-8"))
    return path_yaml


# --------------------------------------------------------------------------- point files
