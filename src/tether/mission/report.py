"""The mission campaign's report: every paradigm side by side, per map and team size.

Reads a sweep folder of ``scenarios/paper/mission.yaml`` (``tether sweep paper/mission``)
and writes into ``--out``:

* ``mission_coverage.png``: the share of the reachable area known at the base station
  over time (median and 25-75 % band over seeds, solid) beside the share the team
  sensed (median, dashed), one panel per map and team size;
* ``mission_latency.png``: the information latency's distribution per paradigm (the
  median over runs of each run's quantile function; cells the base station never
  learnt make a curve stop below 100 %), one panel per map;
* ``mission.md``: the table (means over seeds), the tests between paradigms
  (:func:`tether.experiments.stats.compare_groups`) and every run that did not reach
  the coverage goal or failed, with its seed and cause; ``mission.json``: the numbers.

Run it as ``python -m tether.mission.report SWEEP_FOLDER --out FOLDER``.
"""

from __future__ import annotations

import argparse
import json
import sys
from collections import defaultdict
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from tether.errors import TetherError  # noqa: E402
from tether.experiments.bands import percentiles  # noqa: E402
from tether.experiments.results import load_results, step_series  # noqa: E402
from tether.experiments.stats import compare_groups, describe  # noqa: E402
from tether.mission.metrics import QUANTILES  # noqa: E402

__all__ = ["main", "write_mission_report"]

PARADIGMS = (
    "unconstrained", "recurrent", "utility", "silent_exploration", "continuous_exploration"
)  # fmt: skip
COLOURS = {"unconstrained": "#555555", "recurrent": "#1f77b4", "utility": "#ff7f0e",
           "silent_exploration": "#2ca02c", "continuous_exploration": "#d62728"}  # fmt: skip
COLUMNS = (
    ("base_time_to_50pct_s", "BS 50 % (s)"),
    ("base_time_to_90pct_s", "BS 90 % (s)"),
    ("base_explored_final", "BS final"),
    ("team_explored_final", "team final"),
    ("latency_mean_s", "latency mean (s)"),
    ("latency_undelivered_frac", "undelivered"),
    ("linked_to_base_min", "min linked"),
    ("all_linked_frac", "all linked"),
    ("team_connected_frac", "team conn."),
    ("overlap_rate", "overlap"),
    ("coverage_std", "coverage sd"),
    ("path_length_mean_m", "path (m)"),
)
TESTED = ("base_explored_final", "latency_mean_s")


def _map_name(row: dict[str, Any]) -> str:
    path = str(row.get("param:world.params.path", "map"))
    return Path(path).stem


def _key(row: dict[str, Any]) -> tuple[str, int, str]:
    return _map_name(row), int(row["n_robots"]), str(row["param:strategy.name"])


def _filled(values: np.ndarray) -> np.ndarray:
    """Runs that stopped at the coverage goal keep their last value (not NaN) afterwards."""
    out = values.copy()
    for row in out:
        ok = np.flatnonzero(np.isfinite(row))
        if len(ok):
            row[ok[-1] + 1 :] = row[ok[-1]]
    return out


def _summary(row: dict[str, Any], folder: Path) -> dict[str, Any]:
    path = Path(row["run_dir"]) / "summary.json"
    if not path.is_file():
        path = folder / row["trial_id"] / "summary.json"
    return json.loads(path.read_text())


def _coverage_figure(results: Any, groups: dict, maps: list, sizes: list, out: Path) -> None:
    fig, axes = plt.subplots(len(maps), len(sizes), figsize=(3.6 * len(sizes), 2.8 * len(maps)),
                             squeeze=False, sharey=True, layout="constrained")  # fmt: skip
    for i, name in enumerate(maps):
        for j, n in enumerate(sizes):
            ax = axes[i, j]
            for paradigm in PARADIGMS:
                rows = groups.get((name, n, paradigm))
                if not rows:
                    continue
                colour = COLOURS[paradigm]
                base = step_series(results, rows, "explored_fraction")
                team = step_series(results, rows, "team_explored_fraction")
                if base is not None:
                    t, v = base
                    q = percentiles(_filled(v), axis=0)
                    ax.fill_between(t, 100 * q[1], 100 * q[3], color=colour, alpha=0.2, lw=0)
                    ax.plot(t, 100 * q[2], color=colour, lw=1.4, label=paradigm)
                if team is not None:
                    t, v = team
                    q = percentiles(_filled(v), axis=0)
                    ax.plot(t, 100 * q[2], color=colour, lw=0.9, ls="--")
            ax.set_title(f"{name}, {n} robots", fontsize=9)
            ax.grid(alpha=0.3)
            if i == len(maps) - 1:
                ax.set_xlabel("time (s)")
            if j == 0:
                ax.set_ylabel("area known (%)")
    axes[0, 0].legend(fontsize=7, loc="lower right", title="solid: base station; dashed: team",
                      title_fontsize=7)  # fmt: skip
    fig.savefig(out, dpi=130)
    plt.close(fig)


def _latency_figure(summaries: dict, maps: list, out: Path) -> None:
    fig, axes = plt.subplots(1, len(maps), figsize=(3.8 * len(maps), 3.0), squeeze=False,
                             sharey=True, layout="constrained")  # fmt: skip
    levels = 100 * np.asarray(QUANTILES)
    for j, name in enumerate(maps):
        ax = axes[0, j]
        for paradigm in PARADIGMS:
            curves = [s["latency_quantiles_s"] for (m, _, p), runs in summaries.items()
                      if m == name and p == paradigm for s in runs]  # fmt: skip
            if not curves:
                continue
            q = np.array([[np.inf if v is None else v for v in c] for c in curves], float)
            med = np.median(q, axis=0)
            ok = np.isfinite(med)
            ax.step(med[ok], levels[ok], where="post", color=COLOURS[paradigm], label=paradigm)
        ax.set_xscale("symlog", linthresh=10)
        ax.set_title(name, fontsize=9)
        ax.set_xlabel("information latency (s)")
        ax.grid(alpha=0.3)
    axes[0, 0].set_ylabel("cells delivered within (%)")
    axes[0, 0].legend(fontsize=7, loc="lower right")
    fig.savefig(out, dpi=130)
    plt.close(fig)


def _fmt(value: float, key: str) -> str:
    if not np.isfinite(value):
        return "-"
    if key.endswith("_s") or key.endswith("_m"):
        return f"{value:.0f}"
    return f"{value:.2f}"


def write_mission_report(sweep_dir: str | Path, out_dir: str | Path) -> Path:
    """Figures, table, tests and failures of a mission sweep folder; returns ``mission.md``."""
    results = load_results(sweep_dir)
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    groups: dict[tuple[str, int, str], list[dict[str, Any]]] = defaultdict(list)
    summaries: dict[tuple[str, int, str], list[dict[str, Any]]] = defaultdict(list)
    for row in results.done:
        # the mission metrics are the summary's ``mission`` entry (a dict, not in the table)
        summary = _summary(row, results.folder)
        metrics = {**summary["mission"], "seed": row["seed"], "run_dir": row["run_dir"],
                   "trial_id": row["trial_id"],
                   "controller_success": summary.get("controller_success")}  # fmt: skip
        groups[_key(row)].append(metrics)
        summaries[_key(row)].append(summary["mission"])
    if not groups:
        raise TetherError(f"{sweep_dir}: no finished trial to report; run the sweep first")
    maps = sorted({k[0] for k in groups})
    sizes = sorted({k[1] for k in groups})
    rows_of = defaultdict(list)
    for row in results.done:
        rows_of[_key(row)].append(row)
    _coverage_figure(results, rows_of, maps, sizes, out / "mission_coverage.png")
    _latency_figure(summaries, maps, out / "mission_latency.png")
    lines = [f"Sweep `{results.folder}`: {len(results.done)} finished trials, "
             f"{len(results.failed)} failed.", "",
             "| map | N | paradigm | runs | goal reached | "
             + " | ".join(label for _, label in COLUMNS) + " |",
             "|" + " --- |" * (len(COLUMNS) + 5)]  # fmt: skip
    numbers: dict[str, Any] = {}
    for key in sorted(groups, key=lambda k: (k[0], k[1], PARADIGMS.index(k[2]))):
        rows = groups[key]
        reached = sum(bool(r.get("coverage_goal_reached")) for r in rows)
        cells, entry = [], {"runs": len(rows), "goal_reached": reached}
        for col, _ in COLUMNS:
            d = describe([np.nan if r.get(col) is None else float(r[col]) for r in rows])
            entry[col] = {"n": d.n, "mean": d.mean, "ci": [d.ci_low, d.ci_high]}
            cells.append(_fmt(d.mean, col))
        numbers["/".join(map(str, key))] = entry
        lines.append(f"| {key[0]} | {key[1]} | {key[2]} | {len(rows)} | {reached} | "
                     + " | ".join(cells) + " |")  # fmt: skip
    lines += ["", "Tests between paradigms (per map and team size):", ""]
    for name in maps:
        for n in sizes:
            for metric in TESTED:
                by = {p: [np.nan if r.get(metric) is None else float(r[metric])
                          for r in groups.get((name, n, p), [])] for p in PARADIGMS}  # fmt: skip
                test = compare_groups({p: v for p, v in by.items() if v})
                text = ("too few runs for a test" if test is None else
                        f"{test.test}: statistic {test.statistic:.3g}, p = {test.p_value:.3g}, "
                        f"{test.effect_name} {test.effect:.2f} ({test.reason})")  # fmt: skip
                lines.append(f"- {name}, {n} robots, `{metric}`: {text}")
    judged = [(k, r) for k, rows in sorted(groups.items()) for r in rows
              if r.get("controller_success") is not None]  # fmt: skip
    if judged:
        held = sum(bool(r["controller_success"]) for _, r in judged)
        lines += ["", f"Continuous connectivity held by the controller alone "
                  f"(`controller_success`: no sub-step left the safe set, the guard detecting) "
                  f"in {held} of {len(judged)} runs."]  # fmt: skip
        lines += [f"- not held: {k[0]}, {k[1]} robots, {k[2]}, seed {r['seed']}"
                  for k, r in judged if not r["controller_success"]]  # fmt: skip
    lines += ["", "Runs that did not reach the coverage goal (seed, cause):", ""]
    for key, rows in sorted(groups.items()):
        for r in rows:
            if not r.get("coverage_goal_reached"):
                lines.append(
                    f"- {key[0]}, {key[1]} robots, {key[2]}, seed {r['seed']}: "
                    f"{r.get('stop_reason')} with {100 * float(r['base_explored_final']):.1f} % "
                    f"at the base station ({100 * float(r['team_explored_final']):.1f} % sensed; "
                    f"the base map last grew {r.get('base_idle_at_end_s'):g} s before the end)"
                )
    for r in results.failed:
        lines.append(f"- failed: {results.label(r)}, seed {r.get('seed')}: {r.get('error')}")
    (out / "mission.json").write_text(json.dumps(numbers, indent=1, default=float))
    report = out / "mission.md"
    report.write_text("\n".join(lines) + "\n")
    return report


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m tether.mission.report", description=__doc__)
    parser.add_argument("sweep", help="the sweep folder of paper/mission")
    parser.add_argument("--out", default=None, help="output folder (default: the sweep folder)")
    args = parser.parse_args(argv)
    try:
        path = write_mission_report(args.sweep, args.out or args.sweep)
    except TetherError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    print(f"report: {path}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
