"""A fast CDR encoder for the one large message of an export: a point-list marker.

``rosbags`` builds a Python object per point, which costs about 10 ms for a
MarkerArray of 300 links; a 10,000-step run spends minutes there. Here the
points and colours go in as NumPy arrays. The bytes are those of
``rosbags``' ``serialize_cdr`` for ``visualization_msgs/msg/MarkerArray`` (ROS 2
Humble, little-endian CDR), which ``tests/test_export.py`` checks byte for byte.
"""

from __future__ import annotations

import struct

import numpy as np

_HEADER = b"\x00\x01\x00\x00"  # CDR, little-endian


class CdrWriter:
    """Appends CDR primitives with their alignment (counted after the 4-byte header)."""

    def __init__(self) -> None:
        self.buf = bytearray(_HEADER)

    def align(self, n: int) -> None:
        self.buf += b"\0" * ((-(len(self.buf) - 4)) % n)

    def pack(self, fmt: str, *values: float | int) -> None:
        """``fmt``: ``<`` then primitives of one size (``<3d``, ``<iI``), aligned to that size."""
        self.align(struct.calcsize("<" + fmt.lstrip("<0123456789")[0]))
        self.buf += struct.pack(fmt, *values)

    def string(self, text: str) -> None:
        raw = text.encode() + b"\0"
        self.pack("<I", len(raw))
        self.buf += raw

    def time(self, t_ns: int) -> None:
        self.pack("<iI", t_ns // 10**9, t_ns % 10**9)

    def header(self, t_ns: int, frame_id: str) -> None:
        self.time(t_ns)
        self.string(frame_id)

    def array(self, values: np.ndarray, dtype: str) -> None:
        """A sequence of fixed-size structs of one primitive type (rows of ``values``)."""
        self.pack("<I", len(values))
        if len(values):
            self.align(np.dtype(dtype).itemsize)
            self.buf += np.ascontiguousarray(values, dtype=dtype).tobytes()

    def bytes(self) -> bytes:
        return bytes(self.buf)


def point_marker_array(
    t_ns: int,
    frame_id: str,
    ns: str,
    marker_type: int,
    points_m: np.ndarray,
    colours: np.ndarray,
    scale: float,
    colour: tuple[float, float, float, float] = (1.0, 1.0, 1.0, 1.0),
) -> bytes:
    """A ``MarkerArray`` holding one ADD marker (id 0) of ``points_m`` ``(k, 3)`` with
    per-point ``colours`` ``(k, 4)`` (a LINE_LIST = 5 or SPHERE_LIST = 7), identity pose."""
    w = CdrWriter()
    w.pack("<I", 1)
    w.header(t_ns, frame_id)
    w.string(ns)
    w.pack("<iii", 0, marker_type, 0)
    w.pack("<7d", 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)  # pose: origin, identity
    w.pack("<3d", scale, scale, scale)
    w.pack("<4f", *colour)
    w.pack("<iI", 0, 0)  # lifetime: forever
    w.pack("<?", False)  # frame_locked
    w.array(np.asarray(points_m, dtype=float).reshape(-1, 3), "<f8")
    w.array(np.asarray(colours, dtype=float).reshape(-1, 4), "<f4")
    w.string("")  # texture_resource
    w.header(t_ns, frame_id)  # texture (sensor_msgs/CompressedImage)
    w.string("")
    w.array(np.zeros(0), "u1")
    w.array(np.zeros((0, 2)), "<f4")  # uv_coordinates
    w.string("")  # text
    w.string("")  # mesh_resource
    w.string("")  # mesh_file.filename
    w.array(np.zeros(0), "u1")
    w.pack("<?", False)  # mesh_use_embedded_materials
    return w.bytes()
