"""Run folders: the scenario as run, per-step records, events, summary, figures.

Layout of a run folder::

    run_dir/
      scenario.yaml     the scenario exactly as run (after defaults)
      steps.parquet     one row per step: team metrics of the true graph
      robots.parquet    one row per (step, robot): positions (and velocities)
      events.parquet    one row per event (role changes, plans, elections, ...)
      summary.json      scalar results (see ``Summary`` in the README)
      figures/*.png

Every file is written to a temporary name and renamed into place, so a run
killed mid-write never leaves a half-written file that looks complete.
"""

from __future__ import annotations

import json
import os
import platform
import subprocess
import tempfile
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import yaml

from tether import __version__
from tether.sensing import Observation
from tether.sim import StepRecord, TeamState

_UMASK = os.umask(0)
os.umask(_UMASK)


def _atomic_write(path: Path, write: Any) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    os.close(fd)
    try:
        write(tmp)
        os.chmod(tmp, 0o666 & ~_UMASK)  # mkstemp makes 0600; results are ordinary files
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def _jsonable(value: Any) -> Any:
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_jsonable(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, np.ndarray):
        return _jsonable(value.tolist())
    if isinstance(value, float) and not np.isfinite(value):
        return None if np.isnan(value) else ("inf" if value > 0 else "-inf")
    return value


def git_hash() -> str | None:
    """The git commit of the tether source tree, if it is a checkout."""
    try:
        out = subprocess.run(
            ["git", "rev-parse", "HEAD"],
            cwd=Path(__file__).parent,
            capture_output=True,
            text=True,
            timeout=5,
        )
    except (OSError, subprocess.TimeoutExpired):
        return None
    return out.stdout.strip() or None if out.returncode == 0 else None


def provenance() -> dict[str, Any]:
    """Package version, git hash and machine, recorded with every result."""
    return {
        "tether_version": __version__,
        "git_hash": git_hash(),
        "python": platform.python_version(),
        "platform": platform.platform(),
        "cpu_count": os.cpu_count(),
    }


def machine() -> dict[str, Any]:
    """The machine a measurement ran on (recorded with benchmark and report results)."""
    import datetime as dt

    import scipy

    cpu = platform.processor()
    try:
        with open("/proc/cpuinfo") as fh:
            cpu = next(
                (line.split(":", 1)[1].strip() for line in fh if line.startswith("model name")),
                cpu,
            )
    except OSError:
        pass
    return {
        "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
        "platform": platform.platform(),
        "cpu": cpu,
        "cpu_count": os.cpu_count(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
    }


class RunFolder:
    """Writes the files of one run atomically (see module docstring)."""

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        self.path.mkdir(parents=True, exist_ok=True)

    def write_yaml(self, name: str, data: dict[str, Any]) -> Path:
        target = self.path / name

        def write(tmp: str) -> None:
            with open(tmp, "w") as fh:
                yaml.safe_dump(_jsonable(data), fh, sort_keys=False)

        _atomic_write(target, write)
        return target

    def write_json(self, name: str, data: dict[str, Any]) -> Path:
        target = self.path / name

        def write(tmp: str) -> None:
            with open(tmp, "w") as fh:
                json.dump(_jsonable(data), fh, indent=2)
                fh.write("\n")

        _atomic_write(target, write)
        return target

    def write_table(self, name: str, columns: dict[str, Any]) -> Path:
        """Write columns (equal-length sequences) as a Parquet table."""
        target = self.path / name
        table = pa.table({k: pa.array(np.asarray(v)) for k, v in columns.items()})
        _atomic_write(target, lambda tmp: pq.write_table(table, tmp))
        return target

    def write_rows(self, name: str, rows: list[dict[str, Any]]) -> Path:
        """Write a list of dicts (possibly with differing keys) as a Parquet table."""
        target = self.path / name
        if rows:
            keys = list(dict.fromkeys(k for r in rows for k in r))
            cols = {k: [_jsonable(r.get(k)) for r in rows] for k in keys}
            table = pa.table({k: pa.array(v) for k, v in cols.items()})
        else:
            table = pa.table({"step": pa.array([], pa.int64()), "kind": pa.array([], pa.string())})
        _atomic_write(target, lambda tmp: pq.write_table(table, tmp))
        return target

    def save_figure(self, fig: Any, name: str, dpi: int = 120) -> Path:
        """Write ``fig`` as ``figures/<name>`` (atomically) and close it."""
        import matplotlib.pyplot as plt

        target = self.path / "figures" / name
        try:
            _atomic_write(target, lambda tmp: fig.savefig(tmp, dpi=dpi, format="png"))
        finally:
            plt.close(fig)  # long sweeps would otherwise keep every figure alive
        return target


class TrajectoryRecorder:
    """Collects per-step records of a :func:`tether.sim.simulate` run in memory.

    ``every`` keeps robot positions only every k-th step (team metrics are kept
    at every step); ``keep_positions=False`` drops them altogether (large teams).
    """

    def __init__(self, every: int = 1, keep_positions: bool = True) -> None:
        self.every = max(int(every), 1)
        self.keep_positions = keep_positions
        self.steps: list[StepRecord] = []
        self.position_steps: list[int] = []
        self.positions: list[np.ndarray] = []
        self.links: list[np.ndarray] = []
        self.events: list[dict[str, Any]] = []

    def record(
        self, rec: StepRecord, state: TeamState, obs: Observation, events: list[dict]
    ) -> None:
        self.steps.append(rec)
        self.events.extend(events)
        if self.keep_positions and rec.step % self.every == 0:
            self.position_steps.append(rec.step)
            self.positions.append(state.positions.copy())
            self.links.append(obs.pairs.copy())

    def step_columns(self) -> dict[str, list[Any]]:
        rows = [asdict(r) for r in self.steps]
        return {k: [r[k] for r in rows] for k in rows[0]} if rows else {}

    def robot_columns(self) -> dict[str, np.ndarray]:
        if not self.positions:
            return {"step": np.empty(0, int), "robot": np.empty(0, int)}
        pos = np.stack(self.positions)  # (T, n, dim)
        t, n, dim = pos.shape
        cols: dict[str, np.ndarray] = {
            "step": np.repeat(np.asarray(self.position_steps), n),
            "robot": np.tile(np.arange(n), t),
        }
        for d, axis in zip(range(dim), "xyz", strict=False):
            cols[f"{axis}_m"] = pos[:, :, d].ravel()
        return cols

    def link_columns(self) -> dict[str, np.ndarray]:
        if not self.links:
            return {"step": np.empty(0, int), "i": np.empty(0, int), "j": np.empty(0, int)}
        steps = np.concatenate(
            [np.full(len(lk), s) for s, lk in zip(self.position_steps, self.links, strict=True)]
        )
        both = np.concatenate(self.links).reshape(-1, 2)
        return {"step": steps.astype(int), "i": both[:, 0], "j": both[:, 1]}
