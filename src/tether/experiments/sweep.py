"""Sweeps: the ``sweep:`` block's combinations x seeds, resumable, with one table of trials.

Each trial writes its own run folder ``<out>/<combo>/seed-<s>/`` (see
:mod:`tether.experiments.plan` for the ids); a trial whose ``summary.json`` exists is
not run again, so a killed sweep resumes where it stopped without losing or redoing
work (run folders are committed whole). The folder is a store
(:mod:`tether.experiments.store`): a changed scenario is refused, never mixed in.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from contextlib import closing, nullcontext
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.parquet as pq

from tether.config import Scenario, sweep_label, sweep_spec
from tether.errors import OutputError, TetherError
from tether.experiments.executors import Trial, TrialOutcome, check_executor, execute
from tether.experiments.plan import check_combinations, trial_id, trial_scenario, trials_of
from tether.experiments.progress import LineProgress, TrialProgress
from tether.experiments.store import SWEEP_SCENARIO, SWEEP_TABLE, locked_store, open_store
from tether.runfolder import save_figure, write_rows
from tether.viz.plots import TIME_LABEL, links_over_time, series_over_time

__all__ = [
    "SWEEP_SCENARIO",
    "SWEEP_TABLE",
    "SweepResult",
    "TrialsFailed",
    "TrialsOutcome",
    "prepare_sweep_folder",
    "run_sweep",
    "run_trials",
    "sweep_figures",
    "trial_scenario",
    "trials_of",
]

#: kept for callers of the first sweep API: the store opens (or refuses) the folder
prepare_sweep_folder = open_store


@dataclass
class SweepResult:
    """What a sweep did: its table, trials finished (now or before), reused, figures, failed."""

    table: Path
    n_runs: int
    n_skipped: int
    figures: list[Path] = field(default_factory=list)
    n_failed: int = 0


class TrialsFailed(RuntimeError):
    """Some trials of a sweep failed with internal errors (bugs, a plug-in's exception).

    The message is one line; ``details`` holds the first failure's traceback.
    Failures caused by bad input are raised as :class:`TetherError` instead.
    """

    def __init__(self, message: str, details: str | None = None) -> None:
        super().__init__(message)
        self.details = details


@dataclass
class TrialsOutcome:
    """Summaries of the finished trials by run folder, failures as one line each."""

    summaries: dict[str, dict[str, Any]]
    errors: list[str]
    n_skipped: int
    failures: dict[str, TrialOutcome] = field(default_factory=dict)


def run_trials(
    trials: list[Trial],
    *,
    executor: str = "serial",
    workers: int | None = None,
    address: str | None = None,
    progress: Callable[[str], None] | TrialProgress | None = None,
) -> TrialsOutcome:
    """Run the trials whose run folder has no ``summary.json`` yet; reuse the others.

    Run folders are committed whole (:class:`tether.runfolder.RunFolder`), so
    a folder with ``summary.json`` is a finished trial: a killed sweep resumes
    without losing or redoing work. A trial that fails in any way is recorded
    (``errors``, one line each with its seed; ``failures`` by run folder) and
    the others go on. ``progress`` is a :class:`TrialProgress` or a callable
    given one line per trial.
    """
    summaries: dict[str, dict[str, Any]] = {}
    todo = []
    for trial in trials:
        summary_file = Path(trial.run_dir) / "summary.json"
        try:
            summaries[trial.run_dir] = json.loads(summary_file.read_text())
        except (OSError, ValueError):  # missing, unreadable or damaged: run the trial
            todo.append(trial)
    reporter = LineProgress(progress) if callable(progress) else progress
    errors: list[str] = []
    failures: dict[str, TrialOutcome] = {}
    if reporter is not None:
        reporter.start(len(todo), len(trials) - len(todo))
    try:
        outcomes = execute(todo, executor, workers=workers, address=address)
        stop = closing(outcomes) if hasattr(outcomes, "close") else nullcontext()
        with stop:  # an interrupt stops the executor's workers at once
            for outcome in outcomes:
                run_dir = outcome.trial.run_dir
                if outcome.summary is None:
                    errors.append(f"{run_dir} (seed {outcome.trial.seed}): {outcome.error}")
                    failures[run_dir] = outcome
                else:
                    summaries[run_dir] = outcome.summary
                if reporter is not None:
                    done = len(summaries) - (len(trials) - len(todo))
                    reporter.advance(outcome, done, len(errors))
    finally:
        if reporter is not None:
            reporter.stop()
    return TrialsOutcome(summaries, errors, len(trials) - len(todo), failures)


def trial_rows(
    out: Path, trials: list[tuple[dict[str, Any], Trial]], done: TrialsOutcome
) -> list[dict[str, Any]]:
    """One row per trial: ``trial_id``, ``status`` (done / failed), ``seed``, ``param:``
    values, the run's summary (scalars) or ``error``, and ``run_dir``."""
    rows: list[dict[str, Any]] = []
    for combo, trial in trials:
        params = {f"param:{k}": v for k, v in combo.items()}
        head = {"trial_id": trial_id(out, trial)}
        summary = done.summaries.get(trial.run_dir)
        if summary is not None:
            flat = {k: v for k, v in summary.items() if not isinstance(v, dict | list)}
            flat.pop("seed", None)
            row = {**head, "status": "done", "seed": trial.seed, **params, **flat, "error": None}
        else:
            failure = done.failures.get(trial.run_dir)
            error = failure.error if failure is not None else "not run"
            row = {**head, "status": "failed", "seed": trial.seed, **params, "error": error}
        rows.append({**row, "run_dir": trial.run_dir})
    return rows


def run_sweep(
    scenario: Scenario,
    out_dir: str | Path,
    *,
    seeds: int | list[int] | None = None,
    executor: str = "serial",
    workers: int | None = None,
    address: str | None = None,
    progress: Callable[[str], None] | TrialProgress | None = None,
) -> SweepResult:
    """Run every combination of the ``sweep:`` block for every seed, into a trusted store.

    Before any trial: the block is parsed and every combination is built at the first
    seed (:func:`tether.experiments.plan.check_combinations`, as ``tether validate``
    does), and the folder is opened as a store (a changed scenario is refused). Trials
    whose run folder already holds ``summary.json`` are reused; the others run on
    ``executor`` (see :mod:`tether.experiments.executors`). The table
    ``sweep.parquet`` has one row per trial, finished or failed (``status``,
    ``seed``, ``error``), and is written even when some fail; then the first failure
    is raised in one line: a :class:`TetherError` if every failure was bad input, else
    :class:`TrialsFailed` (an internal error).

    Parameters
    ----------
    seeds : int or list of int, optional
        A count (from the scenario's ``seed``) or a list; default: the block's
        ``seeds``, else one seed.
    """
    check_executor(executor, workers, address)
    trials = trials_of(scenario, out_dir, seeds)
    check_combinations(scenario, seeds)
    with locked_store(scenario, out_dir) as out:  # one sweep per folder at a time
        done = run_trials(
            [t for _, t in trials], executor=executor, workers=workers, address=address,
            progress=progress,
        )  # fmt: skip
        rows = trial_rows(out, trials, done)
        finished = [r for r in rows if r["status"] == "done"]
        try:
            table = write_rows(out / SWEEP_TABLE, rows)
            followers = sweep_spec(scenario).followers()
            drawn = sweep_figures(finished, scenario.team.n_robots, scenario.name, followers)
            figures = [save_figure(fig, out / "figures" / name) for fig, name in drawn]
        except OSError as exc:
            raise OutputError(
                f"{out}: cannot write the sweep table ({exc.strerror or exc})"
            ) from None
    errors = done.errors
    if errors:
        more = f" (and {len(errors) - 1} more)" if len(errors) > 1 else ""
        message = f"{errors[0]}{more}; every trial is in {table} (columns status, error)"
        internal = [f for f in done.failures.values() if f.internal]
        if internal:
            raise TrialsFailed(message, internal[0].details)
        raise TetherError(message)
    return SweepResult(table, len(finished), done.n_skipped, figures, len(errors))


# per-step column -> (x column, figure name, y label, scale); one figure per column runs record
_SWEEP_FIGURES = {
    "n_links": ("t_s", "links.png", "number of links", 1.0),
    "explored_fraction": ("t_s", "explored.png", "explored area known at the BS (%)", 100.0),
}


def sweep_figures(
    rows: list[dict[str, Any]],
    n_robots: int,
    name: str | None = None,
    followers: set[str] | frozenset[str] = frozenset(),
) -> list[tuple[Any, str]]:
    """Per-step metrics of the first seed of each combination, one line per combination.

    Links over time (the silent paper's Fig. 5) and, where runs record it, the
    explored area (exploration strategies), in the one look of :mod:`tether.viz.plots`.
    A combination is labelled by its axes less ``followers`` (zipped axes named by
    their group's first axis).
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
            label = sweep_label({k[6:]: v for k, v in row.items()
                                 if k.startswith("param:") and k[6:] not in followers})  # fmt: skip
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
