"""Parameter grids x seeds over one scenario, resumable, with a comparison table.

Each trial writes its own run folder ``<out>/<combo>/seed-<k>/``; a trial whose
``summary.json`` exists is not run again, so a killed sweep resumes where it
stopped without losing or redoing work (run folders are committed whole).
"""

from __future__ import annotations

import itertools
import json
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.parquet as pq

from tether.config import Scenario, scenario_from_dict, set_dotted
from tether.errors import TetherError
from tether.experiments.executors import Trial, execute
from tether.runfolder import save_figure, write_rows
from tether.viz.plots import TIME_LABEL, links_over_time, series_over_time


@dataclass
class SweepResult:
    table: Path
    n_runs: int
    n_skipped: int
    figures: list[Path] = field(default_factory=list)


def combinations(sweep: dict[str, list[Any]]) -> list[dict[str, Any]]:
    """All combinations of the sweep grid, in a stable order (one empty dict if no grid)."""
    keys = list(sweep)
    return [dict(zip(keys, values, strict=True)) for values in itertools.product(*sweep.values())]


def combo_label(combo: dict[str, Any]) -> str:
    if not combo:
        return "base"
    return ",".join(f"{k.rsplit('.', 1)[-1]}={v}" for k, v in combo.items())


def trial_scenario(base: Scenario, combo: dict[str, Any]) -> Scenario:
    data = base.model_dump(mode="json")
    data.pop("sweep", None)
    for key, value in combo.items():
        set_dotted(data, key, value)
    return scenario_from_dict(data, f"{base.source} [{combo_label(combo)}]", base.base_dir)


def trials_of(
    scenario: Scenario, out_dir: str | Path, seeds: int = 1
) -> list[tuple[dict[str, Any], Trial]]:
    """The sweep's trials, each with its grid combination, in a stable order (combos x seeds)."""
    out = Path(out_dir)
    trials = []
    for combo in combinations(scenario.sweep):
        trial = trial_scenario(scenario, combo)
        data = trial.model_dump(mode="json")
        for k in range(seeds):
            seed = scenario.seed + k
            run_dir = out / combo_label(combo) / f"seed-{seed}"
            trials.append(
                (combo, Trial(data, trial.source, str(trial.base_dir), seed, str(run_dir)))
            )
    return trials


@dataclass
class TrialsOutcome:
    """Summaries of the finished trials by run folder, failures as one line each."""

    summaries: dict[str, dict[str, Any]]
    errors: list[str]
    n_skipped: int


def run_trials(
    trials: list[Trial],
    *,
    executor: str = "serial",
    workers: int | None = None,
    address: str | None = None,
    progress: Callable[[str], None] | None = None,
) -> TrialsOutcome:
    """Run the trials whose run folder has no ``summary.json`` yet; reuse the others.

    Run folders are committed whole (:class:`tether.runfolder.RunFolder`), so
    a folder with ``summary.json`` is a finished trial: a killed sweep resumes
    without losing or redoing work.
    """
    summaries: dict[str, dict[str, Any]] = {}
    todo = []
    for trial in trials:
        summary_file = Path(trial.run_dir) / "summary.json"
        if summary_file.exists():
            summaries[trial.run_dir] = json.loads(summary_file.read_text())
        else:
            todo.append(trial)
    errors: list[str] = []
    for k, outcome in enumerate(execute(todo, executor, workers=workers, address=address), 1):
        run_dir = outcome.trial.run_dir
        if outcome.summary is None:
            errors.append(f"{run_dir}: {outcome.error}")
        else:
            summaries[run_dir] = outcome.summary
        if progress:
            status = "failed" if outcome.summary is None else "done"
            progress(f"[{k}/{len(todo)}] {run_dir} {status}")
    return TrialsOutcome(summaries, errors, len(trials) - len(todo))


def run_sweep(
    scenario: Scenario,
    out_dir: str | Path,
    *,
    seeds: int = 1,
    executor: str = "serial",
    workers: int | None = None,
    address: str | None = None,
    progress: Callable[[str], None] | None = None,
) -> SweepResult:
    """Run every combination of ``scenario.sweep`` for ``seeds`` seeds.

    Trials whose run folder already holds ``summary.json`` are reused; the others run
    on ``executor`` (see :mod:`tether.experiments.executors`). The table
    ``sweep.parquet`` is written from every finished trial even when some fail; then
    the first failure is raised as a one-line :class:`TetherError`.
    """
    trials = trials_of(scenario, out_dir, seeds)
    done = run_trials(
        [t for _, t in trials], executor=executor, workers=workers, address=address,
        progress=progress,
    )  # fmt: skip
    summaries, errors, n_skipped = done.summaries, done.errors, done.n_skipped
    rows: list[dict[str, Any]] = []
    for combo, trial in trials:
        if trial.run_dir not in summaries:
            continue
        summary = summaries[trial.run_dir]
        flat = {k: v for k, v in summary.items() if not isinstance(v, dict | list)}
        rows.append(
            {**{f"param:{k}": v for k, v in combo.items()}, **flat, "run_dir": trial.run_dir}
        )
    table = write_rows(Path(out_dir) / "sweep.parquet", rows)
    drawn = sweep_figures(rows, scenario.team.n_robots, scenario.name)
    figures = [save_figure(fig, Path(out_dir) / "figures" / name) for fig, name in drawn]
    if errors:
        more = f" (and {len(errors) - 1} more)" if len(errors) > 1 else ""
        raise TetherError(f"{errors[0]}{more}; finished trials are in {table}")
    return SweepResult(table, len(rows), n_skipped, figures)


# per-step column -> (x column, figure name, y label, scale); one figure per column runs record
_SWEEP_FIGURES = {
    "n_links": ("t_s", "links.png", "number of links", 1.0),
    "explored_fraction": ("t_s", "explored.png", "explored area known at the BS (%)", 100.0),
}


def sweep_figures(
    rows: list[dict[str, Any]], n_robots: int, name: str | None = None
) -> list[tuple[Any, str]]:
    """Per-step metrics of the first seed of each combination, one line per combination.

    Links over time (the silent paper's Fig. 5) and, where runs record it, the
    explored area (exploration strategies), in the one look of :mod:`tether.viz.plots`.
    """
    files = [Path(r["run_dir"]) / "steps.parquet" for r in rows]
    files = [f for f in files if f.exists()]
    if not files:
        return []
    columns = set(pq.read_schema(files[0]).names)
    prefix = f"{name}: " if name else ""
    out = []
    for metric, (x_col, fig_name, ylabel, scale) in _SWEEP_FIGURES.items():
        if metric not in columns:
            continue
        series: dict[str, tuple[np.ndarray, np.ndarray]] = {}
        for row in rows:
            label = combo_label({k[6:]: v for k, v in row.items() if k.startswith("param:")})
            steps_file = Path(row["run_dir"]) / "steps.parquet"
            if label in series or not steps_file.exists():
                continue
            table = pq.read_table(steps_file, columns=[x_col, metric]).to_pydict()
            series[label] = (np.asarray(table[x_col]), scale * np.asarray(table[metric]))
        title = f"{prefix}{ylabel.split(' (')[0]}, first seed of each combination"
        if metric == "n_links":
            out.append((links_over_time(series, n_robots, title=title), fig_name))
        else:
            out.append((series_over_time(series, TIME_LABEL, ylabel, title=title), fig_name))
    return out
