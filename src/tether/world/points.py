"""Obstacle point files: ``.npy``, ``.csv`` and ``.xyz`` (the ``user_points`` scene).

Every problem with a file is raised as :class:`~tether.errors.MapError` with a
single line naming the file and the fix.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from tether.errors import MapError

__all__ = ["POINT_SUFFIXES", "load_points"]


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
        raise MapError.at(path, None, "file not found")
    suffix = path.suffix.lower()
    if suffix == ".npy":
        try:
            points = np.load(path, allow_pickle=False)
        except (ValueError, OSError) as exc:
            raise MapError.at(path, None, f"not a readable .npy array ({exc})") from None
        if points.dtype.kind not in "iuf":
            raise MapError.at(path, None, f"must hold numbers (got dtype {points.dtype})")
    elif suffix in (".csv", ".xyz"):
        points = _read_text_points(path, "," if suffix == ".csv" else None)
    else:
        raise MapError.at(
            path,
            None,
            f"unsupported points file type {suffix or '(none)'!r}; use .npy, .csv or .xyz",
        )
    points = np.asarray(points, dtype=float)
    if points.ndim != 2 or points.shape[1] not in (2, 3):
        raise MapError.at(
            path,
            None,
            f"must be an array of x y [z] rows, shape (m, 2) or (m, 3) (got {points.shape})",
        )
    if len(points) == 0:
        raise MapError.at(path, None, "holds no points")
    if not np.isfinite(points).all():
        row = int(np.flatnonzero(~np.isfinite(points).all(axis=1))[0])
        raise MapError.at(path, None, f"point {row} is not finite ({points[row].tolist()})")
    return points


def _read_text_points(path: Path, delimiter: str | None) -> np.ndarray:
    try:
        lines = path.read_text(encoding="utf-8").splitlines()
    except UnicodeDecodeError:
        raise MapError.at(path, None, "not a text file of x y [z] rows") from None
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
            raise MapError.at(
                path, f"line {number}", f"expected 2 or 3 {expect} (got {text[:40]!r})"
            ) from None
        if len(values) not in (2, 3) or (rows and len(values) != len(rows[0])):
            want = len(rows[0]) if rows else "2 or 3"
            raise MapError.at(
                path, f"line {number}", f"expected {want} {expect} (got {len(values)})"
            )
        rows.append(values)
    return np.asarray(rows, dtype=float).reshape(-1, len(rows[0]) if rows else 2)
