"""Pack a run into the compact binary payload of the browser replay.

The page carries one gzip-compressed buffer (base64 in the HTML) holding typed
arrays, and a small JSON description of them. Positions are quantized to 16
bits over the run's bounding box (a 100 m scene: 1.5 mm steps) and stored robot
by robot as differences between frames, which gzip shrinks to little for
smoothly moving robots. Links are per-frame index pairs (8-bit indices up to 255
nodes). Long runs are thinned to every k-th frame until the whole page fits its
byte budget; side-plot series are kept at full rate up to 20,000 points.
"""

from __future__ import annotations

import base64
import gzip
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from tether.viewing.known import NEVER, first_seen
from tether.viewing.runfolder import RunData, frame_indices
from tether.viz import style
from tether.viz.boxes import coarsen, obstacle_boxes

MISSING = 65535
MAX_SERIES_POINTS = 20_000
MAX_MAP_CELLS_PER_SIDE = 1024
SERIES = ("lambda2", "n_links", "explored_fraction", "n_connected")


@dataclass
class Payload:
    meta: dict[str, Any]
    blob_b64: str
    stride: int
    n_frames_shown: int
    frame_bytes: int  # compressed bytes of the frame-dependent arrays (estimate)


@dataclass
class _Arrays:
    items: list[tuple[str, np.ndarray]] = field(default_factory=list)

    def add(self, name: str, arr: np.ndarray) -> None:
        self.items.append((name, np.ascontiguousarray(arr)))

    def pack(self) -> tuple[list[dict[str, Any]], bytes]:
        layout, chunks, offset = [], [], 0
        for name, arr in self.items:
            pad = (-offset) % 8
            chunks.append(b"\0" * pad)
            offset += pad
            raw = arr.tobytes()
            layout.append(
                {
                    "name": name,
                    "dtype": arr.dtype.name,
                    "offset": offset,
                    "length": int(arr.size),
                    "shape": list(arr.shape),
                }
            )
            chunks.append(raw)
            offset += len(raw)
        return layout, b"".join(chunks)


def _quantize(pos: np.ndarray, lo: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """``(F, n, 3)`` metres -> ``(3, n, F)`` uint16 differences along frames (wrapping)."""
    q = np.round((pos - lo) / scale)
    q = np.where(np.isfinite(q), np.clip(q, 0, MISSING - 1), MISSING).astype(np.uint16)
    q = q.transpose(2, 1, 0)
    d = q.copy()
    d[:, :, 1:] = q[:, :, 1:] - q[:, :, :-1]  # uint16 arithmetic wraps, as in the page
    return d


def _colour_table(run: RunData) -> tuple[list[str], list[str], np.ndarray | None]:
    """Colour names, hex colours and per-(frame, robot) indices (None: one colour each)."""
    if run.roles is not None:
        role_map = style.role_colour_map(np.unique(run.roles))
        names = list(role_map)
        index = {r: k for k, r in enumerate(names)}
        idx = np.vectorize(index.get, otypes=[np.uint8])(run.roles)
        return [f"robot: {r}" for r in names], [role_map[r] for r in names], idx
    if run.connected is not None:
        names = ["robot, connected to BS", "robot, out of comm"]
        return names, [style.CONNECTED, style.DISCONNECTED], (~run.connected).astype(np.uint8)
    return ["robot"], [style.ROBOT], None


def _series(run: RunData) -> tuple[list[dict[str, Any]], list[tuple[str, np.ndarray]]]:
    steps = run.steps
    if "step" not in steps or not len(steps["step"]):
        return [], []
    step = np.asarray(steps["step"])
    keep = frame_indices(len(step), max_frames=MAX_SERIES_POINTS)
    arrays = [("series_t", run.step_times_s(step[keep]).astype(np.float32))]
    info = []
    for name in SERIES:
        if name in steps:
            values = np.asarray(steps[name], dtype=np.float64)[keep]
            arrays.append((f"series_{name}", values.astype(np.float32)))
            info.append({"name": name, "label": name.replace("_", " ")})
    return info, arrays


def _world(run: RunData, shown: np.ndarray, arrays: _Arrays) -> dict[str, Any]:
    grid = run.grid
    if grid is None:
        return {"kind": "none"}
    if grid.dim == 3:
        boxes = obstacle_boxes(grid)
        arrays.add("boxes", boxes.astype(np.float32))
        top = float(grid.bounds_m[1, 2])
        return {"kind": "boxes", "n": len(boxes), "top_m": top}
    occ = grid.occupied
    factor = max(1, int(np.ceil(max(occ.shape) / MAX_MAP_CELLS_PER_SIDE)))
    arrays.add("map_occupied", coarsen(occ, factor).T.astype(np.uint8))  # rows along y
    info: dict[str, Any] = {
        "kind": "map",
        "nx": int(np.ceil(occ.shape[0] / factor)),
        "ny": int(np.ceil(occ.shape[1] / factor)),
        "cell_m": grid.resolution_m * factor,
        "origin_m": [float(v) for v in grid.origin_m[:2]],
        "known": "none",
    }
    fs, exact = first_seen(run)
    if fs is not None:
        if factor > 1:  # a coarse cell is known as soon as any of its cells is
            pad = [(0, (-s) % factor) for s in fs.shape]
            big = np.pad(fs, pad, constant_values=NEVER)
            fs = big.reshape(big.shape[0] // factor, factor, big.shape[1] // factor, factor)
            fs = fs.min(axis=(1, 3))
        shown_idx = np.searchsorted(shown, np.minimum(fs, run.n_frames), side="left")
        shown_idx = np.where(fs >= NEVER, np.iinfo(np.uint32).max, shown_idx)
        arrays.add("map_first_seen", shown_idx.T.astype(np.uint32))
        info["known"] = "exact" if exact else "approx"
    return info


def _frames(run: RunData, shown: np.ndarray, lo: np.ndarray, scale: np.ndarray) -> _Arrays:
    arrays = _Arrays()
    pos = np.zeros((len(shown), run.n_robots, 3))
    pos[:, :, : run.dim] = run.positions_m[shown]
    arrays.add("frame_steps", run.frame_steps[shown].astype(np.int32))
    arrays.add("frame_t", run.frame_times_s[shown].astype(np.float32))
    arrays.add("pos", _quantize(pos, lo, scale))
    counts = np.diff(run.link_offsets)[shown]
    offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.uint32)
    sel = np.concatenate([np.arange(run.link_offsets[k], run.link_offsets[k + 1]) for k in shown])
    sel = sel.astype(np.int64)
    pairs = run.link_pairs[sel]
    arrays.add("link_off", offsets)
    arrays.add("link_ij", pairs.astype(np.uint8 if run.n_robots + 1 < 256 else np.uint16))
    if run.link_weights is not None:
        margins = np.concatenate([run.link_margins(int(k)) for k in shown]) if len(sel) else []
        arrays.add("link_w", np.round(np.asarray(margins) * 255).astype(np.uint8))
    _, _, idx = _colour_table(run)
    if idx is not None:
        arrays.add("colour_idx", idx[shown].astype(np.uint8))
    return arrays


def _compress(raw: bytes) -> bytes:
    return gzip.compress(raw, compresslevel=6, mtime=0)


def build_payload(run: RunData, *, budget_bytes: int, fixed_bytes: int = 0) -> Payload:
    """The replay's data, thinned to every k-th frame until the page fits ``budget_bytes``
    (``fixed_bytes``: the rest of the page, i.e. the renderer and the template)."""
    ext = run.extent_m(pad=0.02)
    lo = np.zeros(3)
    hi = np.ones(3)
    lo[: run.dim], hi[: run.dim] = ext[0], ext[1]
    scale = np.maximum((hi - lo) / (MISSING - 1), 1e-6)
    names, colours, _ = _colour_table(run)
    series_info, series_arrays = _series(run)

    def attempt(stride: int) -> tuple[dict[str, Any], bytes, int, np.ndarray]:
        shown = frame_indices(run.n_frames, stride=stride)
        frames = _frames(run, shown, lo, scale)
        frame_bytes = len(_compress(frames.pack()[1]))
        arrays = _Arrays(list(frames.items))
        for name, arr in series_arrays:
            arrays.add(name, arr)
        world = _world(run, shown, arrays)
        layout, raw = arrays.pack()
        meta = _meta(run, shown, stride, lo, scale, names, colours, series_info, world, layout)
        return meta, _compress(raw), frame_bytes, shown

    stride = 1
    for _ in range(12):
        meta, blob, frame_bytes, shown = attempt(stride)
        total = fixed_bytes + len(blob) * 4 // 3 + 4096
        if total <= budget_bytes or len(shown) <= 2:
            break
        room = budget_bytes - fixed_bytes - (len(blob) - frame_bytes) * 4 // 3 - 4096
        if room <= 0:
            stride = max(run.n_frames, 1)
            continue
        stride = max(stride + 1, int(np.ceil(stride * frame_bytes * 4 / 3 / room * 1.05)))
    meta["notes"] = list(run.notes)
    return Payload(meta, base64.b64encode(blob).decode("ascii"), stride, len(shown), frame_bytes)


def _meta(
    run: RunData,
    shown: np.ndarray,
    stride: int,
    lo: np.ndarray,
    scale: np.ndarray,
    names: list[str],
    colours: list[str],
    series_info: list[dict[str, Any]],
    world: dict[str, Any],
    layout: list[dict[str, Any]],
) -> dict[str, Any]:
    def pts(a: np.ndarray | None) -> list[list[float]] | None:
        if a is None:
            return None
        out = np.zeros((len(a), 3))
        d = min(a.shape[1], 3)
        out[:, :d] = a[:, :d]
        return out.round(4).tolist()

    ext = run.extent_m(pad=0.02)
    box = np.zeros((2, 3))
    box[:, : run.dim] = ext
    if world.get("kind") == "boxes":
        box[1, 2] = max(box[1, 2], world["top_m"])
    focus = np.zeros((2, 3))
    focus[:, : run.dim] = run.extent_m(pad=0.02, world=False)
    return {
        "name": run.name,
        "strategy": run.summary.get("strategy", ""),
        "n_robots": run.n_robots,
        "dim": run.dim,
        "n_frames": len(shown),
        "n_frames_recorded": run.n_frames,
        "stride": stride,
        "steps": int(run.summary.get("steps", run.frame_steps[-1] if run.n_frames else 0)),
        "range_m": run.range_m,
        "leader": run.leader,
        "base_m": pts(None if run.base_m is None else run.base_m[None, :]),
        "planned_path_m": pts(run.planned_path_m),
        "targets_m": pts(run.targets_m),
        "target_frames": None
        if run.targets is None
        else run.targets.first_frames(run.frame_steps[shown], run.frame_times_s[shown]).tolist(),
        "extent_m": box.tolist(),
        "focus_m": focus.tolist(),
        "quant": {"lo": lo.tolist(), "scale": scale.tolist(), "missing": MISSING},
        "colours": {"names": names, "hex": colours},
        "palette": style.palette(),
        "series": series_info,
        "world": world,
        "arrays": layout,
        "link_weights": run.link_weights is not None,
    }
