"""Parameter grids x seeds over one scenario, resumable, with a comparison table.

Each trial writes its own run folder ``<out>/<combo>/seed-<k>/``; a trial whose
``summary.json`` exists is not run again, so a killed sweep resumes where it
stopped without losing or redoing work (run folders are committed whole).
"""

from __future__ import annotations

import itertools
import json
import math
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.parquet as pq

from tether.config import (
    MAX_SEED,
    MAX_SWEEP_TRIALS,
    Scenario,
    scenario_from_dict,
    set_dotted,
    sweep_label,
)
from tether.errors import OutputError, TetherError
from tether.experiments.executors import Trial, TrialOutcome, check_executor, execute
from tether.runfolder import is_run_folder, save_figure, write_rows, write_yaml
from tether.runner import check_sweep, strategy_class
from tether.viz.plots import TIME_LABEL, links_over_time, series_over_time

#: the scenario of a sweep, written first into its folder (marks the folder as a sweep's)
SWEEP_SCENARIO = "sweep.yaml"
SWEEP_TABLE = "sweep.parquet"


@dataclass
class SweepResult:
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


def combinations(sweep: dict[str, list[Any]]) -> list[dict[str, Any]]:
    """All combinations of the sweep grid, in a stable order (one empty dict if no grid)."""
    keys = list(sweep)
    return [dict(zip(keys, values, strict=True)) for values in itertools.product(*sweep.values())]


def combo_label(combo: dict[str, Any]) -> str:
    """The folder name of a combination (see :func:`tether.config.sweep_label`)."""
    return sweep_label(combo)


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
    if isinstance(seeds, bool) or not isinstance(seeds, int) or seeds < 1:
        raise ValueError(f"seeds must be a positive integer (got {seeds!r})")
    n_combos = math.prod(len(v) for v in scenario.sweep.values())
    if n_combos * seeds > MAX_SWEEP_TRIALS:
        raise TetherError(
            f"{scenario.source}: sweep: {n_combos:,} combinations x {seeds:,} seeds = "
            f"{n_combos * seeds:,} trials; at most {MAX_SWEEP_TRIALS:,} (use fewer seeds or values)"
        )
    if scenario.seed + seeds - 1 > MAX_SEED:
        raise TetherError(
            f"{scenario.source}: seed: {scenario.seed} + {seeds} seeds passes 2**63 - 1; "
            "use a smaller seed"
        )
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
    failures: dict[str, TrialOutcome] = field(default_factory=dict)


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
    without losing or redoing work. A trial that fails in any way is recorded
    (``errors``, one line each with its seed; ``failures`` by run folder) and
    the others go on.
    """
    summaries: dict[str, dict[str, Any]] = {}
    todo = []
    for trial in trials:
        summary_file = Path(trial.run_dir) / "summary.json"
        try:
            summaries[trial.run_dir] = json.loads(summary_file.read_text())
        except FileNotFoundError:
            todo.append(trial)
        except (OSError, ValueError):  # unreadable or damaged: run the trial again
            todo.append(trial)
    errors: list[str] = []
    failures: dict[str, TrialOutcome] = {}
    for k, outcome in enumerate(execute(todo, executor, workers=workers, address=address), 1):
        run_dir = outcome.trial.run_dir
        if outcome.summary is None:
            errors.append(f"{run_dir} (seed {outcome.trial.seed}): {outcome.error}")
            failures[run_dir] = outcome
        else:
            summaries[run_dir] = outcome.summary
        if progress:
            status = f"failed: {outcome.error}" if outcome.summary is None else "done"
            progress(f"[{k}/{len(todo)}] {run_dir} {status}")
    return TrialsOutcome(summaries, errors, len(trials) - len(todo), failures)


def prepare_sweep_folder(scenario: Scenario, out_dir: str | Path) -> Path:
    """Create ``out_dir`` for a sweep (or reuse a sweep's), and write the swept scenario.

    Refused with :class:`OutputError`: a file, a non-empty folder that is not a
    sweep's (so ``--out .`` never mixes a sweep into other files), a place that
    cannot be created or written.
    """
    out = Path(out_dir)
    try:
        if out.exists() and not out.is_dir():
            raise OutputError(f"{out}: exists and is not a folder; choose another --out")
        if out.is_dir() and any(out.iterdir()) and not _is_sweep_folder(out):
            raise OutputError(
                f"{out}: folder is not empty and not a tether sweep folder; choose a new or "
                "empty folder for --out (a sweep resumes only in its own folder)"
            )
        out.mkdir(parents=True, exist_ok=True)
        write_yaml(out / SWEEP_SCENARIO, scenario.model_dump(mode="json"))
    except OSError as exc:
        raise OutputError(
            f"{out}: cannot write the sweep folder ({exc.strerror or exc}); choose a writable --out"
        ) from None
    return out


def _is_sweep_folder(out: Path) -> bool:
    if (out / SWEEP_SCENARIO).is_file() or (out / SWEEP_TABLE).is_file():
        return True
    return any(
        is_run_folder(run) for combo in out.iterdir() if combo.is_dir()
        for run in combo.glob("seed-*")
    )  # fmt: skip


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
    ``sweep.parquet`` has one row per trial, finished or failed (its ``seed`` and
    ``error``, null for a finished one), and is written even when some fail; then
    the first failure is raised in one line: a :class:`TetherError` if every
    failure was bad input, else :class:`TrialsFailed` (an internal error).
    """
    check_executor(executor, workers, address)
    check_sweep(scenario, strategy_class(scenario))
    trials = trials_of(scenario, out_dir, seeds)
    out = prepare_sweep_folder(scenario, out_dir)
    done = run_trials(
        [t for _, t in trials], executor=executor, workers=workers, address=address,
        progress=progress,
    )  # fmt: skip
    summaries, errors, n_skipped = done.summaries, done.errors, done.n_skipped
    rows: list[dict[str, Any]] = []
    finished: list[dict[str, Any]] = []
    for combo, trial in trials:
        params = {f"param:{k}": v for k, v in combo.items()}
        if trial.run_dir in summaries:
            summary = summaries[trial.run_dir]
            flat = {k: v for k, v in summary.items() if not isinstance(v, dict | list)}
            row = {**params, **flat, "run_dir": trial.run_dir, "error": None}
            finished.append(row)
        else:
            failure = done.failures.get(trial.run_dir)
            error = failure.error if failure is not None else "not run"
            row = {**params, "seed": trial.seed, "run_dir": trial.run_dir, "error": error}
        rows.append(row)
    try:
        table = write_rows(out / SWEEP_TABLE, rows)
        drawn = sweep_figures(finished, scenario.team.n_robots, scenario.name)
        figures = [save_figure(fig, out / "figures" / name) for fig, name in drawn]
    except OSError as exc:
        raise OutputError(f"{out}: cannot write the sweep table ({exc.strerror or exc})") from None
    if errors:
        more = f" (and {len(errors) - 1} more)" if len(errors) > 1 else ""
        message = f"{errors[0]}{more}; every trial is in {table} (column error)"
        internal = [f for f in done.failures.values() if f.internal]
        if internal:
            raise TrialsFailed(message, internal[0].details)
        raise TetherError(message)
    return SweepResult(table, len(finished), n_skipped, figures, len(errors))


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
