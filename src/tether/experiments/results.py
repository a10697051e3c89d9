"""A finished sweep folder read back: its trials, axes, summary metrics and per-step records.

What :mod:`tether.experiments.report` draws and tests; nothing here computes statistics.
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.parquet as pq

from tether.config import sweep_label
from tether.errors import TetherError
from tether.experiments.store import STORE_FILE, SWEEP_SCENARIO, SWEEP_TABLE
from tether.sweepspec import SweepError, parse_sweep
from tether.yamlfile import read_yaml

__all__ = ["SweepResults", "load_results", "step_series"]

#: columns that are not results of a trial (ids, bookkeeping) or measure the machine
NOT_METRICS = {
    "trial_id", "status", "seed", "error", "run_dir", "scenario", "strategy",
    "wall_time_s", "cpu_time_s", "planning_time_mean_s", "planning_time_max_s",
}  # fmt: skip
#: per-step columns that are not metrics (the clock)
STEP_CLOCK = ("step", "t_s")


def _is_done(row: dict[str, Any]) -> bool:
    return row.get("status", "done") == "done" and not row.get("error")


@dataclass
class SweepResults:
    """The trials of a sweep folder.

    Attributes
    ----------
    folder : Path
    scenario : dict
        ``sweep.yaml`` (the scenario with its sweep block).
    rows : list of dict
        Every row of ``sweep.parquet``.
    axes : list of str
        The swept keys (``param:`` columns without the prefix), in table order.
    scenario_hash : str or None
    """

    folder: Path
    scenario: dict[str, Any]
    rows: list[dict[str, Any]]
    axes: list[str]
    scenario_hash: str | None = None

    @property
    def done(self) -> list[dict[str, Any]]:
        """The finished trials."""
        return [r for r in self.rows if _is_done(r)]

    @property
    def failed(self) -> list[dict[str, Any]]:
        """The failed trials."""
        return [r for r in self.rows if not _is_done(r)]

    @property
    def shown_axes(self) -> list[str]:
        """The axes that name a combination: a zip group is named by its first axis.

        The other axes of a group move with the first (``sensing.range_m`` with
        ``world.scene`` in Fig. 9), so labels and figures use the first only -- unless
        its values repeat within the group, when it alone would not tell rows apart.
        """
        followers = _zip_followers(self.scenario)
        return [a for a in self.axes if a not in followers]

    def label(self, row: dict[str, Any], axes: list[str] | None = None) -> str:
        """A row's combination as ``leaf=value,...`` over ``axes`` (default: shown axes)."""
        keys = self.shown_axes if axes is None else axes
        return sweep_label({k: row.get(f"param:{k}") for k in keys}) if keys else "all trials"

    def numeric_axes(self) -> list[str]:
        """Shown axes whose finished values are all numbers, with two or more distinct values."""
        out = []
        for axis in self.shown_axes:
            values = [r.get(f"param:{axis}") for r in self.done]
            numbers = all(isinstance(v, int | float) and not isinstance(v, bool) for v in values)
            if values and numbers and len(set(values)) > 1:
                out.append(axis)
        return out

    def metrics(self) -> list[str]:
        """Summary columns that are numbers (or booleans) and vary over the finished trials.

        The column a team-size axis sets (``n_robots`` for ``team.n_robots``) is left out.
        """
        return [key for key, finite in self._numeric_columns().items() if len(set(finite)) > 1]

    def constant_metrics(self) -> dict[str, float | bool]:
        """Summary columns that are numbers (or booleans) with one value over every finished
        trial (``connected_all_steps`` true, ``collisions`` 0, ...), with that value."""
        out: dict[str, float | bool] = {}
        for key, finite in self._numeric_columns().items():
            if len(set(finite)) == 1:
                value = self.done[0].get(key)
                out[key] = value if isinstance(value, bool) else finite[0]
        return out

    def _numeric_columns(self) -> dict[str, list[float]]:
        """Metric columns (numbers or booleans) -> their finite values over finished trials."""
        done = self.done
        if not done:
            return {}
        leaves = {axis.rsplit(".", 1)[-1] for axis in self.axes}
        out = {}
        for key in done[0]:
            if key in NOT_METRICS or key.startswith("param:") or key in leaves:
                continue
            values = [r.get(key) for r in done]
            if not all(isinstance(v, int | float) for v in values if v is not None):
                continue
            out[key] = [float(v) for v in values if v is not None and np.isfinite(float(v))]
        return out


def _zip_followers(scenario: dict[str, Any]) -> set[str]:
    """The axes of the sweep's zip groups after the first, where the first tells rows apart."""
    try:
        return parse_sweep(scenario.get("sweep") or {}).followers()
    except SweepError:
        return set()


def load_results(folder: str | Path) -> SweepResults:
    """Read a sweep folder written by ``tether sweep``.

    Raises
    ------
    TetherError
        The folder holds no ``sweep.parquet`` (one line naming the folder and the fix).
    """
    path = Path(folder)
    table = path / SWEEP_TABLE
    if not table.is_file():
        raise TetherError(
            f"{path}: not a finished sweep folder (no {SWEEP_TABLE}); run "
            f"`tether sweep SCENARIO --out {path}` first"
        )
    try:
        rows = pq.read_table(table).to_pylist()
    except (OSError, ValueError) as exc:
        reason = " ".join(str(exc).split())[:120]
        raise TetherError(
            f"{table}: cannot read the sweep table ({reason}); run the sweep again"
        ) from None
    scenario: dict[str, Any] = {}
    try:
        loaded = read_yaml(path / SWEEP_SCENARIO, str(path / SWEEP_SCENARIO))
        scenario = loaded if isinstance(loaded, dict) else {}
    except (OSError, TetherError):
        pass
    try:
        store_hash = json.loads((path / STORE_FILE).read_text()).get("scenario_hash")
    except (OSError, ValueError, AttributeError):
        store_hash = None
    axes = [k[6:] for k in (rows[0] if rows else {}) if k.startswith("param:")]
    return SweepResults(path, scenario, rows, axes, store_hash)


def step_series(
    results: SweepResults, rows: list[dict[str, Any]], column: str
) -> tuple[np.ndarray, np.ndarray] | None:
    """``(t, values[seed, step])`` of a per-step column over the runs of ``rows``.

    Runs are aligned on their recorded times; shorter runs are padded with NaN.
    None when no run records the column.
    """
    runs = []
    for row in rows:
        steps = Path(row["run_dir"]) / "steps.parquet"
        if not steps.is_file():
            steps = results.folder / row["trial_id"] / "steps.parquet"  # a moved folder
        try:
            if column not in pq.read_schema(steps).names:
                continue
            data = pq.read_table(steps, columns=["t_s", column]).to_pydict()
        except (OSError, ValueError, KeyError):
            continue
        values = np.array([np.nan if v is None else float(v) for v in data[column]])
        runs.append((np.asarray(data["t_s"], dtype=float), values))
    if not runs:
        return None
    longest = max(runs, key=lambda r: r[0].size)[0]
    out = np.full((len(runs), longest.size), np.nan)
    for k, (_, values) in enumerate(runs):
        out[k, : values.size] = values
    return longest, out


def step_columns(rows: list[dict[str, Any]], folder: Path) -> list[str]:
    """The numeric per-step columns the first finished run records (clock left out)."""
    for row in rows:
        steps = Path(row["run_dir"]) / "steps.parquet"
        if not steps.is_file():
            steps = folder / row["trial_id"] / "steps.parquet"
        try:
            schema = pq.read_schema(steps)
        except (OSError, ValueError):
            continue
        return [
            f.name for f in schema
            if f.name not in STEP_CLOCK
            and (str(f.type).startswith(("int", "uint", "double", "float")))
        ]  # fmt: skip
    return []
