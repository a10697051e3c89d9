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
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from tether.errors import MapError
from tether.world.grid import OccupancyGrid

__all__ = [
    "MapLayers",
    "load_map",
    "load_map_layers",
    "load_points",
    "read_image",
    "save_map",
]

MODES = ("trinary", "scale", "raw")
_YAML_SUFFIXES = (".yaml", ".yml")
_IMAGE_HINT = "not a readable PNG/PGM image"


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


def _fail(path: Path | str, field_name: str | None, message: str) -> MapError:
    """A one-line :class:`MapError` ``"<file>: <field>: <message>"``."""
    message = " ".join(str(message).split())
    where = f"{path}: {field_name}: " if field_name else f"{path}: "
    return MapError(where + message)


# --------------------------------------------------------------------------- images


def _read_pgm(data: bytes) -> tuple[np.ndarray, int]:
    """Parse a binary (P5) or plain (P2) PGM, 8 or 16 bit; raise ``ValueError``."""
    magic = data[:2]
    if magic == b"P2":
        text = re.sub(rb"#[^\r\n]*", b" ", data[2:])
        tokens = text.split()
        if len(tokens) < 3:
            raise ValueError("PGM header is incomplete (need width, height, maxval)")
        width, height, maxval = (_header_int(t) for t in tokens[:3])
        _check_header(width, height, maxval)
        body = tokens[3 : 3 + width * height]
        if len(body) < width * height:
            raise ValueError(
                f"PGM data truncated: expected {width * height} values, got {len(body)}"
            )
        try:
            values = np.array([int(t) for t in body], dtype=np.int64)
        except ValueError:
            raise ValueError("PGM pixel values must be integers") from None
    elif magic == b"P5":
        fields: list[int] = []
        pos = 2
        while len(fields) < 3:
            while pos < len(data) and (data[pos : pos + 1].isspace() or data[pos] == ord("#")):
                if data[pos] == ord("#"):
                    while pos < len(data) and data[pos] not in b"\r\n":
                        pos += 1
                else:
                    pos += 1
            start = pos
            while pos < len(data) and data[pos : pos + 1].isdigit():
                pos += 1
            if start == pos:
                raise ValueError("PGM header is incomplete (need width, height, maxval)")
            fields.append(int(data[start:pos]))
        width, height, maxval = fields
        _check_header(width, height, maxval)
        pos += 1  # exactly one whitespace character ends the header
        dtype = np.dtype(">u2") if maxval > 255 else np.dtype("u1")
        need = width * height * dtype.itemsize
        raster = data[pos : pos + need]
        if len(raster) < need:
            raise ValueError(f"PGM data truncated: expected {need} bytes, got {len(raster)}")
        values = np.frombuffer(raster, dtype=dtype).astype(np.int64)
    else:
        raise ValueError("not a P2 or P5 PGM file")
    if values.min(initial=0) < 0:
        raise ValueError(f"PGM pixel values must not be negative (got {int(values.min())})")
    if values.max(initial=0) > maxval:
        raise ValueError(f"PGM pixel value {int(values.max())} exceeds maxval {maxval}")
    return values.reshape(height, width).astype(float), maxval


def _header_int(token: bytes) -> int:
    if not token.isdigit():
        raise ValueError(f"PGM header field {token[:20]!r} is not a positive integer")
    return int(token)


def _check_header(width: int, height: int, maxval: int) -> None:
    if width <= 0 or height <= 0:
        raise ValueError(f"PGM size must be positive (got {width} x {height})")
    if not 0 < maxval < 65536:
        raise ValueError(f"PGM maxval must be in 1..65535 (got {maxval})")


def _read_pillow(path: Path) -> tuple[np.ndarray, int]:
    """Read any image Pillow understands; colour -> channel mean, alpha dropped."""
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(path) as image:
            image.load()
            mode = image.mode
            if mode == "1":
                image = image.convert("L")
            elif mode in ("P", "PA", "CMYK", "YCbCr", "LAB", "HSV"):
                image = image.convert("RGBA" if "A" in mode or mode == "P" else "RGB")
            array = np.asarray(image)
            mode = image.mode
    except UnidentifiedImageError:
        raise ValueError("cannot identify image file") from None
    except (OSError, SyntaxError) as exc:
        raise ValueError(str(exc) or type(exc).__name__) from None
    if mode == "F":
        raise ValueError("floating-point images are not supported; save as 8/16-bit grey")
    if mode.startswith("I"):
        maxval = 65535
    elif array.dtype == np.uint8:
        maxval = 255
    else:
        raise ValueError(f"unsupported image mode {mode!r}")
    array = array.astype(float)
    if array.ndim == 3:
        colour = array[..., :3] if array.shape[2] >= 3 else array[..., :1]
        array = colour.mean(axis=2)
    if array.size == 0:
        raise ValueError("image is empty")
    return np.clip(array, 0, maxval), maxval


def read_image(path: str | Path) -> tuple[np.ndarray, int]:
    """Pixel values of an occupancy image, as stored (row 0 = top).

    Parameters
    ----------
    path
        A PGM (P2/P5, 8 or 16 bit, read by a small built-in reader) or any
        image Pillow can read (PNG in particular).

    Returns
    -------
    values, maxval
        ``(rows, cols)`` float array (channel mean for colour images, alpha
        ignored) and the image's maximum value (255 or 65535, or the PGM's
        ``maxval``).

    Raises
    ------
    MapError
        File missing or unreadable.
    """
    path = Path(path)
    if not path.is_file():
        raise _fail(path, None, "file not found")
    with open(path, "rb") as handle:
        head = handle.read(2)
    try:
        if head in (b"P2", b"P5"):
            return _read_pgm(path.read_bytes())
        return _read_pillow(path)
    except ValueError as exc:
        raise _fail(path, None, f"{_IMAGE_HINT} ({exc})") from None


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
        raise _fail(source, name, f"must be a number (got {value!r})")
    return float(value)


def _positive(source: Path, name: str, value: Any) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not value > 0:
        raise _fail(source, name, f"must be a positive number (got {value!r})")
    if not math.isfinite(value):
        raise _fail(source, name, f"must be a positive number (got {value!r})")
    return float(value)


def _fraction(source: Path, name: str, value: Any) -> float:
    number = _number(source, name, value)
    if not 0.0 <= number <= 1.0:
        raise _fail(source, name, f"must be a number between 0 and 1 (got {value!r})")
    return number


def _flag(source: Path, name: str, value: Any) -> bool:
    if isinstance(value, bool):
        return value
    if isinstance(value, int) and value in (0, 1):
        return bool(value)
    raise _fail(source, name, f"must be 0/1 or true/false (got {value!r})")


def _origin(source: Path, name: str, value: Any) -> np.ndarray:
    if value is None:
        return np.zeros(2)
    values = np.asarray(value).tolist() if isinstance(value, np.ndarray) else value
    if not isinstance(values, (list, tuple)) or len(values) not in (2, 3):
        raise _fail(source, name, f"must be a list [x, y, yaw] of numbers (got {value!r})")
    numbers = [_number(source, name, v) for v in values]
    if len(numbers) == 3 and numbers[2] != 0.0:
        raise _fail(
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
        raise _fail(
            source, "free_thresh", f"must not exceed occupied_thresh (got {fre!r} > {occ!r})"
        )
    return occ, fre


def _read_yaml(path: Path) -> dict[str, Any]:
    try:
        doc = yaml.safe_load(path.read_text(encoding="utf-8"))
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" at line {mark.line + 1}" if mark is not None else ""
        problem = getattr(exc, "problem", None) or "syntax error"
        raise _fail(path, None, f"not valid YAML{where}: {problem}") from None
    except UnicodeDecodeError:
        raise _fail(
            path, None, "not a text YAML file (is it an image? use the .png/.pgm)"
        ) from None
    if not isinstance(doc, dict):
        raise _fail(
            path,
            None,
            "must be a mapping with ROS map_server keys (image, resolution, origin, ...)",
        )
    for key in ("image", "resolution"):
        if key not in doc:
            raise _fail(path, key, "required key missing (see ROS map_server's map YAML format)")
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
        raise _fail(path, None, "file not found")
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
        raise _fail(path, "image", f"must be a file name such as map.pgm (got {image_name!r})")
    image = Path(image_name)
    if not image.is_absolute():
        image = path.parent / image
    if not image.is_file():
        raise _fail(path, "image", f"file {image_name!r} not found next to the YAML")
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
        raise _fail(path, "mode", f"must be one of {', '.join(MODES)} (got {mode!r})")
    try:
        values, maxval = read_image(image)
    except MapError as exc:
        reason = str(exc).split(": ", 1)[-1]
        raise _fail(path, "image", f"{image_name!r}: {reason}") from None
    meta = {"source": str(path), "image": str(image), "mode": mode}
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
        raise _fail(
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
    with open(path_image, "wb") as handle:
        handle.write(f"P5\n# written by tether\n{cols} {rows}\n255\n".encode("ascii"))
        handle.write(np.ascontiguousarray(image).tobytes())
    doc = {
        "image": path_image.name,
        "mode": "trinary",
        "resolution": float(grid.resolution_m),
        "origin": [float(grid.origin_m[0]), float(grid.origin_m[1]), 0.0],
        "negate": 0,
        "occupied_thresh": 0.65,
        "free_thresh": 0.196,
    }
    path_yaml.write_text(yaml.safe_dump(doc, sort_keys=False), encoding="utf-8")
    return path_yaml


# --------------------------------------------------------------------------- point files

POINT_SUFFIXES = (".npy", ".csv", ".xyz")


def load_points(path: str | Path) -> np.ndarray:
    """Obstacle points from a ``.npy``, ``.csv`` or ``.xyz`` file.

    Parameters
    ----------
    path
        ``.npy``: a numeric array of shape ``(m, 2)`` or ``(m, 3)``.
        ``.csv``: comma-separated ``x,y[,z]`` rows, optional header line
        (e.g. ``x,y,z``), ``#`` comments. ``.xyz``: whitespace-separated
        ``x y [z]`` rows, ``#`` comments.

    Returns
    -------
    np.ndarray
        ``(m, dim)`` float array, ``dim`` 2 or 3, at least one point, all finite.

    Raises
    ------
    MapError
        One line naming the file (and line) and what is expected.
    """
    path = Path(path)
    if not path.is_file():
        raise _fail(path, None, "file not found")
    suffix = path.suffix.lower()
    if suffix == ".npy":
        try:
            points = np.load(path, allow_pickle=False)
        except (ValueError, OSError) as exc:
            raise _fail(path, None, f"not a readable .npy array ({exc})") from None
        if points.dtype.kind not in "iuf":
            raise _fail(path, None, f"must hold numbers (got dtype {points.dtype})")
    elif suffix in (".csv", ".xyz"):
        points = _read_text_points(path, "," if suffix == ".csv" else None)
    else:
        raise _fail(
            path,
            None,
            f"unsupported points file type {suffix or '(none)'!r}; use .npy, .csv or .xyz",
        )
    points = np.asarray(points, dtype=float)
    if points.ndim != 2 or points.shape[1] not in (2, 3):
        raise _fail(
            path,
            None,
            f"must be an array of x y [z] rows, shape (m, 2) or (m, 3) (got {points.shape})",
        )
    if len(points) == 0:
        raise _fail(path, None, "holds no points")
    if not np.isfinite(points).all():
        row = int(np.flatnonzero(~np.isfinite(points).all(axis=1))[0])
        raise _fail(path, None, f"point {row} is not finite ({points[row].tolist()})")
    return points


def _read_text_points(path: Path, delimiter: str | None) -> np.ndarray:
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except UnicodeDecodeError:
        raise _fail(path, None, "not a text file of x y [z] rows") from None
    rows: list[list[float]] = []
    expect = "numbers separated by commas" if delimiter else "numbers separated by spaces"
    for number, line in enumerate(lines, start=1):
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        tokens = [t.strip() for t in text.split(delimiter)]
        try:
            values = [float(t) for t in tokens]
        except ValueError:
            if not rows and delimiter and all(t.isidentifier() for t in tokens):
                continue  # a CSV header such as "x,y,z"
            raise _fail(
                path, f"line {number}", f"expected 2 or 3 {expect} (got {text[:40]!r})"
            ) from None
        if len(values) not in (2, 3) or (rows and len(values) != len(rows[0])):
            want = len(rows[0]) if rows else "2 or 3"
            raise _fail(path, f"line {number}", f"expected {want} {expect} (got {len(values)})")
        rows.append(values)
    return np.asarray(rows, dtype=float).reshape(-1, len(rows[0]) if rows else 2)
