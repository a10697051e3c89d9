"""``tether export``: a run as ROS 2 messages, written without a ROS install.

Messages are ROS 2 Humble types serialized to CDR by the pure-Python ``rosbags``
package; ``--format mcap`` writes one MCAP file (ROS 2 profile, ``ros2msg``
schemas, the form Foxglove / Lichtblick open and ``ros2 bag play`` reads with the
MCAP storage plugin), ``--format rosbag2`` a rosbag2 folder (``metadata.yaml`` and a
SQLite3 ``.db3``, metadata version 8: Iron and later; on Humble use the MCAP file).

Topics, all in frame ``map`` and stamped with the simulation clock (step time
from ``steps.parquet``'s ``t_s``, else step x dt; the run starts at 0 s):

==========================  ===============================  =================================
topic                       type                             when
==========================  ===============================  =================================
``/tether/robots``          ``geometry_msgs/PoseArray``      every recorded step, robot order
``/tether/robot_markers``   ``visualization_msgs/MarkerArray``  every recorded step: spheres
                                                             coloured by role / leader / BS link
``/tether/links``           ``visualization_msgs/MarkerArray``  every recorded step: a line list
                                                             coloured by margin (green..red)
``/tether/plan``            ``visualization_msgs/MarkerArray``  once: planned path, targets, BS
``/map``                    ``nav_msgs/OccupancyGrid``       once, 2-D worlds (transient local)
``/tether/known_map``       ``nav_msgs/OccupancyGrid``       exploration: when the map grows
``/tether/obstacles``       ``visualization_msgs/MarkerArray``  once, 3-D worlds: obstacle boxes
``/tether/metrics/<name>``  ``std_msgs/Float64``             every step, each numeric column
==========================  ===============================  =================================
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from tether.atomic import safe_file_name
from tether.errors import TetherError
from tether.export.cdr import point_marker_array
from tether.viewing.output import check_target, write_output, write_output_folder
from tether.viewing.runfolder import RunData, load_run
from tether.viz import style

FRAME_ID = "map"
MAX_KNOWN_MAPS = 100
FORMATS = ("mcap", "rosbag2")
STATIC_TOPICS = ("/map", "/tether/plan", "/tether/obstacles")
NUMERIC_KINDS = "biuf"


@dataclass
class Export:
    path: Path
    format: str
    messages: dict[str, int]
    bytes: int
    seconds: float


_ROS2_HINT = "tether export needs the ROS 2 writers: pip install 'tether[ros2]' (rosbags, mcap)"


def _typestore() -> Any:
    try:
        from rosbags.typesys import Stores, get_typestore
    except ImportError:
        raise TetherError(_ROS2_HINT) from None
    return get_typestore(Stores.ROS2_HUMBLE)


def ns_of(t_s: float) -> int:
    return int(round(float(t_s) * 1e9))


class Messages:
    """Builds and serializes the exported messages of one run."""

    def __init__(self, run: RunData) -> None:
        self.run = run
        self.ts = _typestore()
        self.T = self.ts.types
        self.rad = max(0.009 * float(np.max(np.ptp(run.extent_m(world=False), axis=0))), 0.05)
        self.role_map = (
            style.role_colour_map(np.unique(run.roles)) if run.roles is not None else None
        )

    def cdr(self, msg: Any, typename: str) -> bytes:
        return bytes(self.ts.serialize_cdr(msg, typename))

    def header(self, t_s: float) -> Any:
        ns = ns_of(t_s)
        stamp = self.T["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)
        return self.T["std_msgs/msg/Header"](stamp=stamp, frame_id=FRAME_ID)

    def point(self, p: np.ndarray) -> Any:
        z = float(p[2]) if len(p) > 2 else 0.0
        return self.T["geometry_msgs/msg/Point"](x=float(p[0]), y=float(p[1]), z=z)

    def pose(self, p: np.ndarray) -> Any:
        q = self.T["geometry_msgs/msg/Quaternion"](x=0.0, y=0.0, z=0.0, w=1.0)
        return self.T["geometry_msgs/msg/Pose"](position=self.point(p), orientation=q)

    def colour(self, rgba: Any) -> Any:
        r, g, b, a = (float(v) for v in rgba)
        return self.T["std_msgs/msg/ColorRGBA"](r=r, g=g, b=b, a=a)

    def marker(
        self,
        t_s: float,
        ns: str,
        mtype: int,
        *,
        points: list | None = None,
        colours: list | None = None,
        colour: Any = (1, 1, 1, 1),
        scale: float = 0.1,
        pose: np.ndarray | None = None,
        size: np.ndarray | None = None,
        mid: int = 0,
    ) -> Any:
        T = self.T
        sx = sy = sz = scale
        if size is not None:
            sx, sy, sz = (float(v) for v in size)
        return T["visualization_msgs/msg/Marker"](
            header=self.header(t_s),
            ns=ns,
            id=mid,
            type=mtype,
            action=0,
            pose=self.pose(np.zeros(3) if pose is None else pose),
            scale=T["geometry_msgs/msg/Vector3"](x=sx, y=sy, z=sz),
            color=self.colour(colour),
            lifetime=T["builtin_interfaces/msg/Duration"](sec=0, nanosec=0),
            frame_locked=False,
            points=points or [],
            colors=colours or [],
            texture_resource="",
            texture=T["sensor_msgs/msg/CompressedImage"](
                header=self.header(t_s), format="", data=np.zeros(0, np.uint8)
            ),
            uv_coordinates=[],
            text="",
            mesh_resource="",
            mesh_file=T["visualization_msgs/msg/MeshFile"](filename="", data=np.zeros(0, np.uint8)),
            mesh_use_embedded_materials=False,
        )

    def marker_array(self, markers: list[Any]) -> bytes:
        msg = self.T["visualization_msgs/msg/MarkerArray"](markers=markers)
        return self.cdr(msg, "visualization_msgs/msg/MarkerArray")

    # ----------------------------------------------------------- per recorded step
    def robots(self, k: int, t_s: float) -> bytes:
        pos = self.run.positions_m[k]
        poses = [self.pose(p) for p in pos]
        msg = self.T["geometry_msgs/msg/PoseArray"](header=self.header(t_s), poses=poses)
        return self.cdr(msg, "geometry_msgs/msg/PoseArray")

    def xyz(self, points: np.ndarray) -> np.ndarray:
        out = np.zeros((len(points), 3))
        out[:, : points.shape[1]] = points
        return out

    def robot_points(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Robot positions ``(n, 3)`` and their colours ``(n, 4)`` at frame ``k``."""
        run = self.run
        cols = style.robot_colours(
            run.n_robots,
            roles=None if run.roles is None else run.roles[k],
            role_map=self.role_map,
            leader=run.leader,
            connected=None if run.connected is None else run.connected[k],
        )
        return self.xyz(run.positions_m[k]), cols

    def link_points(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """Link end points ``(2m, 3)`` (pairs) and their colours ``(2m, 4)`` at frame ``k``."""
        run = self.run
        lk = run.links(k)
        if not len(lk):
            return np.zeros((0, 3)), np.zeros((0, 4))
        nodes = self.xyz(run.nodes(k))
        pts = np.empty((2 * len(lk), 3))
        pts[0::2], pts[1::2] = nodes[lk[:, 0]], nodes[lk[:, 1]]
        rgba = np.repeat(style.link_colours(run.link_margins(k)), 2, axis=0)
        return pts, rgba

    def robot_markers(self, k: int, t_s: float) -> bytes:
        pts, cols = self.robot_points(k)
        return point_marker_array(ns_of(t_s), FRAME_ID, "robots", 7, pts, cols, 2 * self.rad)

    def links(self, k: int, t_s: float) -> bytes:
        pts, cols = self.link_points(k)
        return point_marker_array(ns_of(t_s), FRAME_ID, "links", 5, pts, cols, 0.25 * self.rad)

    # ----------------------------------------------------------- once
    def plan(self, t_s: float) -> bytes | None:
        run, out = self.run, []
        if run.planned_path_m is not None:
            pts = [self.point(p) for p in run.planned_path_m]
            out.append(
                self.marker(
                    t_s,
                    "planned_path",
                    4,
                    points=pts,
                    colour=style.rgba_floats(style.PATH),
                    scale=0.3 * self.rad,
                )
            )
        if run.targets_m is not None:
            pts = [self.point(p) for p in run.targets_m]
            out.append(
                self.marker(
                    t_s,
                    "targets",
                    7,
                    points=pts,
                    colour=style.rgba_floats(style.TARGET),
                    scale=3 * self.rad,
                )
            )
        if run.base_m is not None:
            out.append(
                self.marker(
                    t_s,
                    "base_station",
                    1,
                    pose=run.base_m,
                    colour=style.rgba_floats(style.BASE_STATION),
                    scale=3 * self.rad,
                )
            )
        return self.marker_array(out) if out else None

    def obstacles(self, t_s: float) -> bytes | None:
        from tether.viz.boxes import obstacle_boxes

        grid = self.run.grid
        if grid is None or grid.dim != 3:
            return None
        top = float(grid.bounds_m[1, 2])
        out = []
        for mid, b in enumerate(obstacle_boxes(grid)):
            rgba = style.HEIGHT_CMAP(b[5] / max(top, 1e-9))
            out.append(
                self.marker(
                    t_s,
                    "obstacles",
                    1,
                    pose=(b[:3] + b[3:]) / 2,
                    size=b[3:] - b[:3],
                    colour=rgba,
                    mid=mid,
                )
            )
        return self.marker_array(out)

    def occupancy(self, t_s: float, values: np.ndarray) -> bytes:
        """``values`` ``(nx, ny)`` int8 (0 free, 100 occupied, -1 unknown) of the run's 2-D grid."""
        grid = self.run.grid
        T = self.T
        ns = ns_of(t_s)
        info = T["nav_msgs/msg/MapMetaData"](
            map_load_time=T["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9),
            resolution=float(grid.resolution_m),
            width=int(values.shape[0]),
            height=int(values.shape[1]),
            origin=self.pose(np.append(grid.origin_m[:2], 0.0)),
        )
        data = np.ascontiguousarray(values.T).ravel().astype(np.int8)  # row-major, x fastest
        msg = T["nav_msgs/msg/OccupancyGrid"](header=self.header(t_s), info=info, data=data)
        return self.cdr(msg, "nav_msgs/msg/OccupancyGrid")

    def scalar(self, value: float) -> bytes:
        return self.cdr(self.T["std_msgs/msg/Float64"](data=float(value)), "std_msgs/msg/Float64")


def _stream(run: RunData, msgs: Messages) -> Iterator[tuple[str, str, int, bytes]]:
    """``(topic, type, time_ns, cdr)`` in time order."""
    times = run.frame_times_s
    t0 = float(times[0]) if len(times) else 0.0
    grid = run.grid
    if grid is not None and grid.dim == 2:
        yield (
            "/map",
            "nav_msgs/msg/OccupancyGrid",
            ns_of(t0),
            msgs.occupancy(t0, np.where(grid.occupied, 100, 0)),
        )
    for topic, build in (("/tether/plan", msgs.plan), ("/tether/obstacles", msgs.obstacles)):
        data = build(t0)
        if data is not None:
            yield topic, "visualization_msgs/msg/MarkerArray", ns_of(t0), data
    known_frames: set[int] = set()
    first = None
    if run.is_exploration and grid is not None and grid.dim == 2:
        from tether.viewing.known import first_seen

        first, _ = first_seen(run)
        if first is not None:
            changed = np.unique(first[first < run.n_frames])
            keep = np.linspace(0, len(changed) - 1, min(len(changed), MAX_KNOWN_MAPS))
            known_frames = {int(changed[int(round(i))]) for i in keep} if len(changed) else set()
    steps = run.steps
    numeric = [
        c
        for c, v in steps.items()
        if c not in ("step", "t_s") and np.asarray(v).dtype.kind in NUMERIC_KINDS
    ]
    step_col = np.asarray(steps.get("step", np.zeros(0, np.int64)))
    step_t = run.step_times_s(step_col) if len(step_col) else np.zeros(0)
    # merge per-step metrics and per-frame messages in time order
    events = [(float(t), 0, i) for i, t in enumerate(step_t)]
    events += [(float(t), 1, k) for k, t in enumerate(times)]
    for t, kind, i in sorted(events):
        if kind == 0:
            for col in numeric:
                v = np.asarray(steps[col])[i]
                if np.isfinite(v):
                    yield f"/tether/metrics/{col}", "std_msgs/msg/Float64", ns_of(t), msgs.scalar(v)
            continue
        k = i
        tn = ns_of(t)
        yield "/tether/robots", "geometry_msgs/msg/PoseArray", tn, msgs.robots(k, t)
        yield (
            "/tether/robot_markers",
            "visualization_msgs/msg/MarkerArray",
            tn,
            msgs.robot_markers(k, t),
        )
        yield "/tether/links", "visualization_msgs/msg/MarkerArray", tn, msgs.links(k, t)
        if first is not None and k in known_frames:
            values = np.where(first <= k, np.where(grid.occupied, 100, 0), -1)
            yield "/tether/known_map", "nav_msgs/msg/OccupancyGrid", tn, msgs.occupancy(t, values)


def _qos_yaml(transient: bool) -> str:
    """rosbag2's offered_qos_profiles YAML (reliable; transient local for static topics)."""
    inf = "    sec: 2147483647\n    nsec: 4294967295\n"
    return (
        "- history: 3\n  depth: 0\n  reliability: 1\n"
        f"  durability: {1 if transient else 2}\n"
        f"  deadline:\n{inf}  lifespan:\n{inf}  liveliness: 1\n"
        f"  liveliness_lease_duration:\n{inf}  avoid_ros_namespace_conventions: false\n"
    )


def _write_mcap(path: Path, stream: Iterator, ts: Any) -> dict[str, int]:
    try:
        from mcap.writer import CompressionType, Writer
    except ImportError:
        raise TetherError(_ROS2_HINT) from None

    counts: dict[str, int] = {}
    schemas: dict[str, int] = {}
    channels: dict[str, int] = {}
    with open(path, "wb") as fh:
        writer = Writer(fh, compression=CompressionType.LZ4)
        writer.start(profile="ros2", library="tether")
        for topic, typename, t_ns, data in stream:
            if topic not in channels:
                if typename not in schemas:
                    text, _ = ts.generate_msgdef(typename, ros_version=2)
                    schemas[typename] = writer.register_schema(
                        name=typename, encoding="ros2msg", data=text.encode()
                    )
                meta = {"offered_qos_profiles": _qos_yaml(topic in STATIC_TOPICS)}
                channels[topic] = writer.register_channel(topic, "cdr", schemas[typename], meta)
            counts[topic] = counts.get(topic, 0) + 1
            writer.add_message(channels[topic], t_ns, data, t_ns, counts[topic] - 1)
        writer.finish()
    return counts


def _write_rosbag2(path: Path, stream: Iterator, ts: Any) -> dict[str, int]:
    try:
        from rosbags.interfaces import (
            Qos,
            QosDurability,
            QosHistory,
            QosLiveliness,
            QosReliability,
            QosTime,
        )
        from rosbags.rosbag2 import Writer
    except ImportError:
        raise TetherError(_ROS2_HINT) from None

    def qos(transient: bool) -> Qos:
        inf = QosTime(sec=2147483647, nsec=4294967295)
        return Qos(
            QosHistory.UNKNOWN,
            0,
            QosReliability.RELIABLE,
            QosDurability.TRANSIENT_LOCAL if transient else QosDurability.VOLATILE,
            inf,
            inf,
            QosLiveliness.AUTOMATIC,
            inf,
            False,
        )

    counts: dict[str, int] = {}
    conns: dict[str, Any] = {}
    with Writer(path, version=8) as writer:
        for topic, typename, t_ns, data in stream:
            if topic not in conns:
                conns[topic] = writer.add_connection(
                    topic,
                    typename,
                    typestore=ts,
                    offered_qos_profiles=[qos(topic in STATIC_TOPICS)],
                )
            writer.write(conns[topic], t_ns, data)
            counts[topic] = counts.get(topic, 0) + 1
    return counts


def export(
    run: RunData | str | Path,
    out: str | Path | None = None,
    *,
    fmt: str = "mcap",
    progress: Callable[[int], None] | None = None,
) -> Export:
    """Export a run folder to ``out`` (default ``RUN_DIR/<name>.mcap`` or ``RUN_DIR/rosbag2``)."""
    start = time.perf_counter()
    fmt = fmt.lower()
    if fmt not in FORMATS:
        raise TetherError(f"--format: expected one of {', '.join(FORMATS)} (got {fmt!r})")
    if not isinstance(run, RunData):
        run = load_run(run)
    msgs = Messages(run)
    if out is None:  # named from data: made a safe file name, always inside the run folder
        out = run.path / (f"{safe_file_name(run.name)}.mcap" if fmt == "mcap" else "rosbag2")
    path = Path(out)
    if fmt == "rosbag2" and (path.exists() or path.is_symlink()):
        raise TetherError(f"{path}: already exists; rosbag2 writes a new folder (remove it first)")
    if fmt == "mcap":
        check_target(path)
    stream = _stream(run, msgs)
    if progress is not None:
        stream = _counted(stream, progress)
    counts: dict[str, int] = {}
    if fmt == "mcap":
        size = write_output(
            path, lambda tmp: counts.update(_write_mcap(Path(tmp), stream, msgs.ts)),
            what="MCAP file", run_dir=run.path,
        )  # fmt: skip
    else:
        size = write_output_folder(
            path, lambda tmp: counts.update(_write_rosbag2(tmp, stream, msgs.ts)),
            what="rosbag2", run_dir=run.path,
        )  # fmt: skip
    return Export(path, fmt, counts, size, time.perf_counter() - start)


def _counted(stream: Iterator, progress: Callable[[int], None]) -> Iterator:
    for item in stream:
        if item[0] == "/tether/robots":
            progress(1)
        yield item
