"""Reading PNG and PGM images (8- and 16-bit) into arrays, with one-line errors.

PGM (P2 and P5, any maxval) is parsed here so that 16-bit maps keep their
depth; everything else goes through Pillow. Used by :mod:`tether.world.maps`.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np

from tether.errors import MapError
from tether.world.grid import MAX_CELLS

_IMAGE_HINT = "not a readable PNG/PGM image"


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
    if width * height > MAX_CELLS:
        raise ValueError(f"{width} x {height} pixels are more than {MAX_CELLS:,}")


def _read_pillow(path: Path) -> tuple[np.ndarray, int]:
    """Read any image Pillow understands; colour -> channel mean, alpha dropped."""
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(path) as image:
            width, height = image.size
            if width * height > MAX_CELLS:
                raise ValueError(
                    f"{width} x {height} pixels are more than {MAX_CELLS:,}; scale the map down"
                )
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
    except Image.DecompressionBombError as exc:
        raise ValueError(str(exc)) from None
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
        raise MapError.at(path, None, "file not found")
    with open(path, "rb") as handle:
        head = handle.read(2)
    try:
        if head in (b"P2", b"P5"):
            return _read_pgm(path.read_bytes())
        return _read_pillow(path)
    except ValueError as exc:
        raise MapError.at(path, None, f"{_IMAGE_HINT} ({exc})") from None
