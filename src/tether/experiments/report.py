"""``tether report SWEEP_DIR``: a Markdown report of a sweep, with figures and statistics.

Writes ``<SWEEP_DIR>/report.md`` and its figures under ``<SWEEP_DIR>/figures/``:

* per numeric axis (e.g. team size) and summary metric, the metric against the axis
  with percentile bands (10/25/50/75/90) over seeds (one colour per value of the
  other axes);
* per per-step metric (links, algebraic connectivity, explored area ...), the metric
  against time with bands over seeds, one colour per combination; the links figure
  shows the spanning-tree count for reference when team size is not swept;
* statistics per summary metric and combination: n, mean, standard deviation and the
  95 % t confidence interval of the mean, then the test between combinations that
  fits the data, with its effect size (:mod:`tether.experiments.stats` says which).

Every number is computed from the trials in the folder when the report is made.
"""

from __future__ import annotations

import datetime as dt
from pathlib import Path
from typing import Any

import numpy as np

from tether import __version__
from tether.errors import OutputError
from tether.experiments.bands import bands_against_axis, bands_over_time
from tether.experiments.results import SweepResults, load_results, step_columns, step_series
from tether.experiments.stats import compare_groups, describe
from tether.runfolder import atomic_write, save_figure

__all__ = ["REPORT", "write_report"]

REPORT = "report.md"
#: at most this many combinations get their own colour in a figure over time
MAX_SERIES = 8
#: per-step columns not worth a figure (flags and counts the summary already gives)
SKIP_STEP = {"connected", "n_components", "collisions"}


def _num(value: float) -> str:
    if value is None or not np.isfinite(value):
        return "-"
    return f"{value:.4g}"


def _groups(results: SweepResults) -> dict[str, list[dict[str, Any]]]:
    groups: dict[str, list[dict[str, Any]]] = {}
    for row in results.done:
        groups.setdefault(results.label(row), []).append(row)
    return groups


def _values(rows: list[dict[str, Any]], metric: str) -> np.ndarray:
    return np.array([float(r[metric]) for r in rows if r.get(metric) is not None], dtype=float)


def _axis_figures(results: SweepResults, figures: Path) -> list[tuple[str, Path]]:
    out = []
    metrics = [m for m in results.metrics() if not isinstance(results.done[0].get(m), bool)]
    for axis in results.numeric_axes():
        others = [a for a in results.shown_axes if a != axis]
        leaf = axis.rsplit(".", 1)[-1]
        for metric in metrics:
            series: dict[str, dict[float, list[float]]] = {}
            for row in results.done:
                if row.get(metric) is None:
                    continue
                label = results.label(row, others) if others else ""
                by_x = series.setdefault(label, {})
                by_x.setdefault(float(row[f"param:{axis}"]), []).append(float(row[metric]))
            if not series:
                continue
            data = {k: {x: np.array(v) for x, v in s.items()} for k, s in series.items()}
            title = f"{results.scenario.get('name', 'sweep')}: {metric} against {leaf}"
            fig = bands_against_axis(data, axis, metric, title)
            path = save_figure(fig, figures / f"bands_{metric}_vs_{leaf}.png")
            out.append((f"{metric} against {axis}", path))
    return out


def _time_figures(results: SweepResults, figures: Path) -> list[tuple[str, Path]]:
    groups = _groups(results)
    if not groups:
        return []
    shown = dict(list(groups.items())[:MAX_SERIES])
    out = []
    n_robots = results.scenario.get("team", {}).get("n_robots")
    team_swept = any(a.startswith("team.n_robots") for a in results.axes)
    for column in step_columns(results.done, results.folder):
        if column in SKIP_STEP:
            continue
        series = {}
        for label, rows in shown.items():
            got = step_series(results, rows, column)
            if got is not None:
                series[label] = got
        if not series:
            continue
        reference = None
        if column == "n_links" and isinstance(n_robots, int) and not team_swept:
            reference = (n_robots - 1, f"spanning tree ({n_robots - 1} links)")
        name = "links" if column == "n_links" else column
        title = f"{results.scenario.get('name', 'sweep')}: {name} over time, bands over seeds"
        ylabel = "number of links" if column == "n_links" else column
        fig = bands_over_time(series, ylabel, title, reference)
        path = save_figure(fig, figures / f"time_{name}.png")
        out.append((f"{name} against time", path))
    return out


def _statistics(results: SweepResults) -> list[str]:
    groups = _groups(results)
    lines = []
    for metric in results.metrics():
        lines += [f"### {metric}", "", "| combination | n | mean | std | 95 % CI |",
                  "|---|---:|---:|---:|---|"]  # fmt: skip
        values = {label: _values(rows, metric) for label, rows in groups.items()}
        for label, x in values.items():
            d = describe(x)
            ci = f"[{_num(d.ci_low)}, {_num(d.ci_high)}]"
            lines.append(f"| {label} | {d.n} | {_num(d.mean)} | {_num(d.std)} | {ci} |")
        test = compare_groups(values) if len(values) > 1 else None
        lines.append("")
        if test is not None:
            extra = f"; {test.extra}" if test.extra else ""
            lines.append(
                f"{test.test}: statistic {_num(test.statistic)}, p = {test.p_value:.3g}; "
                f"{test.effect_name} = {_num(test.effect)}{extra} (chosen: {test.reason})."
            )
        elif len(values) > 1:
            lines.append("No test: fewer than two combinations with 2+ values, or no spread.")
        lines.append("")
    return lines


def _constants(results: SweepResults) -> list[str]:
    """The metrics with one value over every finished trial: a table, not left out."""
    constant = results.constant_metrics()
    if not constant:
        return []
    lines = ["### The same in every finished trial", "",
             "These metrics did not vary, so they have no spread to test.", "",
             "| metric | value |", "|---|---:|"]  # fmt: skip
    for metric, value in constant.items():
        shown = str(value).lower() if isinstance(value, bool) else _num(value)
        lines.append(f"| {metric} | {shown} |")
    return [*lines, ""]


def _controller(results: SweepResults) -> list[str]:
    """Per combination, the trials the controller alone kept in its safe set (the
    ``connectivity`` and ``multi_target`` strategies' ``controller_success``)."""
    if not any("controller_success" in row for row in results.done):
        return []
    lines = ["## Controller success", "",
             "A trial is a success of the controller when its invariants held without the "
             "guard's help: no guard intervention, no sub-step outside the safe set, the "
             "integrator's step rules met (`controller_success`; not measured with the "
             "guard off).", "",
             "| combination | trials | successes | not successes | not measured | "
             "with safe-set exits | with guard interventions |",
             "|---|---:|---:|---:|---:|---:|---:|"]  # fmt: skip
    for label, rows in _groups(results).items():
        flags = [row.get("controller_success") for row in rows]
        exits = sum(1 for row in rows if (row.get("safe_set_exits") or 0) > 0)
        guard = sum(1 for row in rows if (row.get("guard_interventions") or 0) > 0)
        lines.append(f"| {label} | {len(rows)} | {flags.count(True)} | {flags.count(False)} | "
                     f"{flags.count(None)} | {exits} | {guard} |")  # fmt: skip
    return [*lines, ""]


def _header(results: SweepResults, command: str) -> list[str]:
    done, failed = results.done, results.failed
    seeds = sorted({r["seed"] for r in results.rows if r.get("seed") is not None})
    name = results.scenario.get("name", "sweep")
    when = dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds")
    axes = ", ".join(f"`{a}`" for a in results.axes) or "none"
    return [
        f"# Sweep report: {name}",
        "",
        f"Made by `{command}` on {when} (tether {__version__}) from `{results.folder}`; "
        f"scenario hash `{results.scenario_hash or 'not recorded'}`.",
        "",
        f"- trials: {len(results.rows)} ({len(done)} done, {len(failed)} failed)",
        f"- axes: {axes}; combinations: {len(_groups(results)) or 0} with finished trials",
        f"- seeds: {len(seeds)} ({seeds[0]}..{seeds[-1]})" if seeds else "- seeds: none",
        "- trials are paired: one seed gives the same random start on every combination",
        "",
    ]


METHODS = """## Methods

Means with the sample standard deviation (ddof 1) and the 95 % confidence interval of
the mean from Student's t (n - 1 degrees of freedom). Between combinations, the test
fits the data: if every combination looks normal (Shapiro-Wilk p >= 0.05, 3+ values,
not constant), Welch's t-test with Hedges' g for two combinations, one-way ANOVA with
eta squared for more; otherwise Mann-Whitney U with the rank-biserial correlation for
two, Kruskal-Wallis H with epsilon squared for more. The tests treat combinations as
independent samples; trials are paired by seed, so this ignores the pairing (conservative
when paired trials are positively correlated). Computed by `tether.experiments.stats`
(scipy.stats). Bands are percentiles over seeds: line the median, shaded 25-75 and 10-90.
"""


def write_report(sweep_dir: str | Path, command: str | None = None) -> Path:
    """Write ``report.md`` and its figures into a sweep folder; the report's path.

    Parameters
    ----------
    sweep_dir : str or Path
        A folder written by ``tether sweep`` (it holds ``sweep.parquet``).
    command : str, optional
        The command named in the report as its origin (default ``tether report DIR``).
    """
    results = load_results(sweep_dir)
    try:
        return _write_report(results, command)
    except OSError as exc:  # a full disk, a read-only folder: every file is whole or absent
        raise OutputError(
            f"{results.folder}: cannot write the report ({exc.strerror or exc}); free some "
            "space or make the sweep folder writable"
        ) from None


def _write_report(results: Any, command: str | None) -> Path:
    folder = results.folder
    figures = folder / "figures"
    lines = _header(results, command or f"tether report {folder}")
    if results.failed:
        lines += ["## Failed trials", "", "| trial | seed | error |", "|---|---:|---|"]
        for row in results.failed:
            error = str(row.get("error") or "").replace("|", "\\|")
            lines.append(f"| `{row.get('trial_id', row.get('run_dir'))}` | {row.get('seed')} "
                         f"| {error} |")  # fmt: skip
        lines.append("")
    if results.done:
        lines += _controller(results)
        drawn = _axis_figures(results, figures) + _time_figures(results, figures)
        lines += ["## Figures", ""]
        for caption, path in drawn:
            lines += [
                f"![{caption}]({path.relative_to(folder).as_posix()})",
                "",
                f"*{caption}*",
                "",
            ]
        lines += ["## Statistics", "", *_statistics(results), *_constants(results)]
    else:
        lines += ["No trial finished: nothing to draw or test.", ""]
    lines.append(METHODS)
    text = "\n".join(lines)
    target = folder / REPORT

    def write(tmp: str) -> None:
        Path(tmp).write_text(text)

    atomic_write(target, write)
    return target
