"""Read a run folder once into arrays, for the animation, the replay and the export.

Every reader of a run folder (``tether animate``, ``tether view``, ``tether
export``) starts from :func:`load_run`, which codes against "column present or
not" rather than against one strategy's files:

* ``robots.parquet`` must have ``step, robot, x_m, y_m`` (``z_m`` in 3-D); any
  other column becomes a per-robot ``(T, n)`` array in :attr:`RunData.robot_columns`
  (``role`` strings colour robots, ``connected`` marks exploration robots);
* ``links.parquet`` (optional) ``step, i, j`` with an optional ``weight``; an index
  equal to ``n_robots`` is the base station, at ``summary.json["base_m"]``;
* ``steps.parquet`` any per-step columns (``lambda2``, ``n_links``, ...);
* ``events.parquet`` (optional): the targets the run used
  (:mod:`tether.targets_recorded`), else those the scenario lists (goals);
* ``scenario.yaml`` rebuilds the world (the occupancy grid) with the scenario's
  seed, the same way the runner does; a world that cannot be rebuilt (a map file
  that moved) is reported in :attr:`RunData.notes` and the run is shown without it.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.parquet as pq

from tether.errors import TetherError
from tether.limits import memory_budget_bytes
from tether.targets_recorded import (
    TARGET_ADDED,
    TARGET_FINISHED,
    RecordedTargets,
    recorded_targets,
)

_POSITION_COLUMNS = ("x_m", "y_m", "z_m")


class RunFolderError(TetherError):
    """A run folder that is missing or cannot be read (one-line message)."""


@dataclass
class RunData:
    """A run folder as arrays (see module docstring). Frames are the recorded steps."""

    path: Path
    summary: dict[str, Any]
    scenario: Any  # tether.config.Scenario or None
    name: str
    n_robots: int
    dim: int
    dt_s: float
    frame_steps: np.ndarray  # (T,) int
    positions_m: np.ndarray  # (T, n, dim) float
    robot_columns: dict[str, np.ndarray]  # name -> (T, n)
    link_offsets: np.ndarray  # (T + 1,): links of frame k are link_pairs[off[k]:off[k + 1]]
    link_pairs: np.ndarray  # (L, 2) int
    link_weights: np.ndarray | None  # (L,) or None
    steps: dict[str, np.ndarray]  # steps.parquet columns
    range_m: float
    base_m: np.ndarray | None = None
    leader: int | None = None
    planned_path_m: np.ndarray | None = None  # (k, dim)
    targets_m: np.ndarray | None = None  # (k, dim)
    targets: RecordedTargets | None = None  # with when each was added and finished
    grid: Any = None  # tether.world.grid.OccupancyGrid or None
    bounds_m: np.ndarray | None = None  # (2, dim) of the world, if known
    notes: list[str] = field(default_factory=list)

    @property
    def n_frames(self) -> int:
        return len(self.frame_steps)

    @property
    def frame_times_s(self) -> np.ndarray:
        return self.step_times_s(self.frame_steps)

    def step_times_s(self, steps: np.ndarray) -> np.ndarray:
        """Simulation time of steps: from ``steps.parquet``'s ``t_s`` when present."""
        steps = np.asarray(steps)
        if "t_s" in self.steps and "step" in self.steps and len(self.steps["step"]):
            return np.interp(steps, self.steps["step"], self.steps["t_s"])
        return steps * self.dt_s

    @property
    def roles(self) -> np.ndarray | None:
        return self.robot_columns.get("role")

    @property
    def connected(self) -> np.ndarray | None:
        col = self.robot_columns.get("connected")
        return None if col is None else col.astype(bool)

    @property
    def is_exploration(self) -> bool:
        return self.base_m is not None

    def links(self, k: int) -> np.ndarray:
        """``(m, 2)`` links of frame ``k`` (indices into :meth:`nodes`)."""
        return self.link_pairs[self.link_offsets[k] : self.link_offsets[k + 1]]

    def nodes(self, k: int) -> np.ndarray:
        """Positions of frame ``k``'s robots, then the base station if there is one."""
        pos = self.positions_m[k]
        if self.base_m is None:
            return pos
        return np.vstack([pos, self.base_m[None, : self.dim]])

    def link_margins(self, k: int) -> np.ndarray:
        """Per link of frame ``k`` in [0, 1]: the recorded ``weight`` if present (divided by
        the largest weight when weights exceed 1), else ``1 - d / range``."""
        from tether.viz.style import link_margin

        lo, hi = self.link_offsets[k], self.link_offsets[k + 1]
        if self.link_weights is not None:  # weights in [0, 1] as they are, else over the max
            w = self.link_weights[lo:hi]
            top = float(np.nanmax(self.link_weights)) if len(self.link_weights) else 1.0
            return np.clip(w / (top if top > 1.0 else 1.0), 0.0, 1.0)
        lk = self.link_pairs[lo:hi]
        nodes = self.nodes(k)
        d = np.linalg.norm(nodes[lk[:, 0]] - nodes[lk[:, 1]], axis=1)
        return link_margin(d, self.range_m)

    def extent_m(self, pad: float = 0.05, *, world: bool = True) -> np.ndarray:
        """``(2, dim)`` box holding the robots, the base station, path, targets (and world)."""
        pts = [self.positions_m.reshape(-1, self.dim)]
        for extra in (self.base_m, self.planned_path_m, self.targets_m):
            if extra is not None:
                pts.append(np.atleast_2d(extra)[:, : self.dim])
        if world and self.bounds_m is not None and self.grid is not None:
            pts.append(self.bounds_m[:, : self.dim])
        allp = np.vstack(pts)
        allp = allp[np.all(np.isfinite(allp), axis=1)]
        lo, hi = allp.min(axis=0), allp.max(axis=0)
        margin = pad * max(float(np.max(hi - lo)), 1.0)
        return np.stack([lo - margin, hi + margin])


def _read_table(path: Path) -> dict[str, np.ndarray]:
    try:
        table = pq.read_table(path)
    except Exception as exc:  # pyarrow raises several types for corrupt files
        raise RunFolderError(f"{path}: cannot read Parquet file ({exc})") from None
    return {name: table.column(name).to_numpy(zero_copy_only=False) for name in table.schema.names}


def _scenario(path: Path) -> Any:
    from tether.config import load_scenario

    try:
        return load_scenario(path / "scenario.yaml")
    except TetherError:
        return None


def _strategy_params(scenario: Any) -> Any:
    try:
        from tether.runner import strategy_class, strategy_params

        return strategy_params(scenario, strategy_class(scenario))
    except Exception:  # an unknown or changed strategy: fall back to the raw dict
        return None


def _range_m(scenario: Any, params: Any) -> float:
    """Link range for margins: the strategy's link range, else the sensing range."""
    from tether.viz.plots import link_range_m

    value = link_range_m(scenario, params)
    return 1.0 if value is None else value


def _path_and_targets(scenario: Any) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The leader's waypoints and the goals a scenario lists (targets a strategy generates
    are read from the run's events instead)."""
    if scenario is None:
        return None, None
    p = scenario.strategy.params
    path = None
    traj = p.get("trajectory")
    if isinstance(traj, dict) and traj.get("waypoints"):
        path = _points(traj["waypoints"])
    targets = None
    ext = p.get("external")
    if isinstance(ext, dict) and ext.get("kind") == "goal" and ext.get("goals"):
        targets = _points(ext["goals"])
    return path, targets


def _points(value: Any) -> np.ndarray | None:
    """``(k, d)`` floats from a list of points, ``None`` for anything else."""
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        return None
    return arr if arr.ndim == 2 and len(arr) and np.all(np.isfinite(arr)) else None


def _recorded_targets(path: Path, dim: int) -> RecordedTargets | None:
    file = path / "events.parquet"
    if not file.exists():
        return None
    try:
        table = pq.read_table(file)
    except Exception as exc:  # pyarrow raises several types for corrupt files
        raise RunFolderError(f"{file}: cannot read Parquet file ({exc})") from None
    names = table.schema.names
    if "kind" not in names or "position_m" not in names:
        return None
    kinds = pa.array([TARGET_ADDED, *TARGET_FINISHED])
    table = table.filter(pc.is_in(table["kind"], value_set=kinds))
    keep = [c for c in ("step", "kind", "robot", "target", "position_m", "appear_s") if c in names]
    return recorded_targets(table.select(keep).to_pylist(), dim)


def _leader(scenario: Any, path: np.ndarray | None, positions: np.ndarray) -> int | None:
    """The silent strategy's leader: ``params.leader`` or the robot nearest the path start."""
    if scenario is None or not hasattr(scenario, "strategy") or scenario.strategy.name != "silent":
        return None
    given = scenario.strategy.params.get("leader")
    n = positions.shape[1]
    if isinstance(given, int):
        return given % n
    if path is None or not len(positions):
        return None
    start = np.zeros(positions.shape[2])
    start[: min(path.shape[1], len(start))] = path[0, : len(start)]
    return int(np.argmin(np.linalg.norm(positions[0] - start, axis=1)))


def load_world(scenario: Any) -> Any:
    """The scenario's world rebuilt with its seed (the runner's first use of its rng)."""
    from tether.runner import build_world

    return build_world(scenario, np.random.default_rng(scenario.seed))


def _read_summary(file: Path) -> dict[str, Any]:
    """``summary.json`` as a dict ({} if absent); a damaged one is a one-line error."""
    if not file.exists():
        return {}
    try:
        if file.stat().st_size > 16 * 2**20:
            raise ValueError("over 16 MiB")
        data = json.loads(file.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        reason = " ".join(str(getattr(exc, "strerror", None) or exc).split())[:80]
        raise RunFolderError(
            f"{file}: damaged ({reason}); run the scenario again to rewrite its run folder"
        ) from None
    if not isinstance(data, dict):
        raise RunFolderError(
            f"{file}: damaged (expected a JSON object of summary keys); run the scenario again "
            "to rewrite its run folder"
        )
    return data


def load_run(path: str | Path, *, world: bool = True) -> RunData:
    """Read the run folder at ``path`` (see module docstring)."""
    path = Path(path)
    if not path.is_dir():
        raise RunFolderError(f"{path}: not a run folder (no such directory)")
    if not (path / "robots.parquet").exists():
        raise RunFolderError(f"{path}: not a run folder (robots.parquet is missing)")
    summary = _read_summary(path / "summary.json")
    scenario = _scenario(path) if (path / "scenario.yaml").exists() else None
    robots = _read_table(path / "robots.parquet")
    for col in ("step", "robot", "x_m", "y_m"):
        if col not in robots:
            raise RunFolderError(f"{path / 'robots.parquet'}: column {col!r} is missing")
    dim = 3 if "z_m" in robots else 2
    frame_steps, frame_idx = np.unique(robots["step"].astype(np.int64), return_inverse=True)
    robot_idx = robots["robot"].astype(np.int64)
    if len(robot_idx) and robot_idx.min() < 0:
        raise RunFolderError(f"{path / 'robots.parquet'}: column 'robot' has negative indices")
    n = int(robot_idx.max()) + 1 if len(robot_idx) else 0
    listed = summary.get("n_robots")
    if isinstance(listed, int) and not isinstance(listed, bool) and n <= listed <= 2 * n + 1:
        n = listed  # robots never recorded still count (and keep their index)
    t = len(frame_steps)
    if t * n * (dim + 1) * 8 > memory_budget_bytes():
        raise RunFolderError(
            f"{path / 'robots.parquet'}: {t:,} recorded steps of {n:,} robots do not fit in "
            "memory; is the table damaged?"
        )
    positions = np.full((t, n, dim), np.nan)
    for d, col in enumerate(_POSITION_COLUMNS[:dim]):
        positions[frame_idx, robot_idx, d] = robots[col]
    extras: dict[str, np.ndarray] = {}
    for col, values in robots.items():
        if col in ("step", "robot", *_POSITION_COLUMNS):
            continue
        arr = np.empty((t, n), dtype=object if values.dtype == object else values.dtype)
        if arr.dtype == object:
            arr[:] = None
        arr[frame_idx, robot_idx] = values
        extras[col] = arr.astype(str) if arr.dtype == object else arr
    steps = _read_table(path / "steps.parquet") if (path / "steps.parquet").exists() else {}

    base = summary.get("base_m")
    base_m = None
    numbers = isinstance(base, list) and all(
        isinstance(v, int | float) and not isinstance(v, bool) and np.isfinite(v) for v in base
    )
    if base is not None and not (numbers and 2 <= len(base) <= 3):
        raise RunFolderError(
            f"{path / 'summary.json'}: base_m: expected [x, y] or [x, y, z] in metres "
            f"(got {str(base)[:40]!r})"
        )
    if base is not None:
        base_m = np.zeros(dim)
        base_m[: min(dim, len(base))] = np.asarray(base, dtype=float)[:dim]
    offsets, pairs, weights = _links(path, frame_steps, n + (base_m is not None))
    params = _strategy_params(scenario) if scenario is not None else None
    planned, targets = _path_and_targets(scenario)
    recorded = _recorded_targets(path, dim)
    if recorded is not None:
        targets = recorded.positions_m
    dt_s = float(scenario.sim.dt_s) if scenario is not None else 1.0
    data = RunData(
        path=path,
        summary=summary,
        scenario=scenario,
        name=str(summary.get("scenario", scenario.name if scenario else path.name)),
        n_robots=n,
        dim=dim,
        dt_s=dt_s,
        frame_steps=frame_steps,
        positions_m=positions,
        robot_columns=extras,
        link_offsets=offsets,
        link_pairs=pairs,
        link_weights=weights,
        steps=steps,
        range_m=_range_m(scenario, params),
        base_m=base_m,
        planned_path_m=planned,
        targets_m=targets,
        targets=recorded,
    )
    data.leader = _leader(scenario, planned, positions)
    if world and scenario is not None:
        try:
            w = load_world(scenario)
        except Exception as exc:  # a map file that moved must not stop the replay
            data.notes.append(f"world not drawn: {exc}")
        else:
            data.grid = w.grid if w.has_obstacles else None
            data.bounds_m = w.bounds_m
    return data


def _links(
    path: Path, frame_steps: np.ndarray, n_nodes: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    t = len(frame_steps)
    empty = (np.zeros(t + 1, dtype=np.int64), np.zeros((0, 2), dtype=np.int64), None)
    file = path / "links.parquet"
    if not file.exists():
        return empty
    cols = _read_table(file)
    if not {"step", "i", "j"} <= set(cols) or not len(cols["step"]):
        return empty
    step = cols["step"].astype(np.int64)
    pos = np.searchsorted(frame_steps, step)
    ok = (pos < t) & (frame_steps[np.minimum(pos, t - 1)] == step)
    ij = np.stack([cols["i"], cols["j"]], axis=1).astype(np.int64)
    ok &= np.all((ij >= 0) & (ij < n_nodes), axis=1)
    order = np.argsort(pos[ok], kind="stable")
    frame = pos[ok][order]
    pairs = ij[ok][order]
    weights = cols["weight"].astype(float)[ok][order] if "weight" in cols else None
    offsets = np.searchsorted(frame, np.arange(t + 1)).astype(np.int64)
    return offsets, pairs, weights


def frame_indices(
    n_frames: int, *, stride: int | None = None, max_frames: int | None = None
) -> np.ndarray:
    """Frames to show: every ``stride``-th, or evenly thinned to ``max_frames``; the last
    frame is always kept so a replay ends where the run ended."""
    if n_frames <= 0:
        return np.zeros(0, dtype=np.int64)
    if stride is None:
        stride = 1 if not max_frames else max(1, int(np.ceil(n_frames / max_frames)))
    idx = np.arange(0, n_frames, max(int(stride), 1), dtype=np.int64)
    if idx[-1] != n_frames - 1:
        idx = np.append(idx, n_frames - 1)
    return idx
