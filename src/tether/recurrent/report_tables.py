"""Markdown tables of the Figs. 4-6 re-make, computed from the report's run folders.

``python -m tether.recurrent.report_tables OUT_DIR`` prints the tables of
``docs/recurrent.md`` for the runs that :mod:`tether.recurrent.report` wrote under
``OUT_DIR/runs/<map>/<setting>/seed-<k>``: explored area known at the BS after 300,
600 and 900 steps (mean over runs, and mean ± sample sd at the end), the time robots
spend out of communication (steps per robot), and per-plan solver times.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pyarrow.compute as pc
import pyarrow.parquet as pq

__all__ = ["ci95", "markdown", "run_statistics"]

MAPS = {"grass": "Cluttered", "offices": "Office", "open": "Open"}
FIG4 = {
    "apx_t12_timed": "APX, (a) planning time counted",
    "ilp_t12_timed": "ILP, (a) planning time counted",
    "theta12": "APX, (b) instantaneous",
    "ilp_t12_instant": "ILP, (b) instantaneous",
}
FIG5 = ("theta1", "theta3", "theta6", "theta9", "theta12", "utility")


def _runs(out: Path, m: str, setting: str) -> list[Path]:
    return sorted(
        p for p in (out / "runs" / m / setting).glob("seed-*") if (p / "summary.json").exists()
    )


def _explored(run: Path) -> np.ndarray:
    return pq.read_table(run / "steps.parquet").column("explored_fraction").to_numpy()


def _at(curves: list[np.ndarray], step: int) -> float:
    return 100 * float(np.mean([c[min(step, len(c) - 1)] for c in curves]))


def _pm(values: list[float], fmt: str = "{:.1f}") -> str:
    sd = float(np.std(values, ddof=1)) if len(values) > 1 else 0.0
    return f"{fmt.format(np.mean(values))} ± {fmt.format(sd)}"


def ci95(values: list[float | None]) -> tuple[float | None, float | None]:
    """Mean and half-width of its 95 % confidence interval (Student t), ``None`` if undefined.

    ``None`` values (e.g. a share of the map never reached) are left out.
    """
    from scipy.stats import t

    v = np.asarray([x for x in values if x is not None], dtype=float)
    if len(v) == 0:
        return None, None
    if len(v) < 2:
        return float(v.mean()), None
    half = t.ppf(0.975, len(v) - 1) * v.std(ddof=1) / np.sqrt(len(v))
    return float(v.mean()), float(half)


def _mean(values: list) -> float | None:
    v = [x for x in values if x is not None]
    return float(np.mean(v)) if v else None


#: summary keys of issue 13 that every setting's runs are summarized by
TIME_TO = ("time_to_50pct_s", "time_to_75pct_s", "time_to_90pct_s")
SHARES = ("time_moving_frac", "time_relaying_frac", "time_waiting_frac", "time_returning_frac")


def run_statistics(summaries: list[dict]) -> dict:
    """Per-setting statistics of the new summary keys: 95 % CIs, time shares, episodes."""
    out: dict = {}
    for key in ("final_explored_fraction", "out_of_comm_mean_steps"):
        mu, half = ci95([s.get(key) for s in summaries])
        out[f"{key}_ci95"] = [mu, half]
    for key in TIME_TO:
        out[key] = [s.get(key) for s in summaries]
    for key in SHARES:
        out[f"{key}_mean"] = _mean([s.get(key) for s in summaries])
    for key in ("out_of_comm_episodes", "out_of_comm_longest_steps"):
        out[f"{key}_mean"] = _mean([s.get(key) for s in summaries])
    return out


def _plan_times(runs: list[Path]) -> np.ndarray:
    times = []
    for run in runs:
        events = pq.read_table(run / "events.parquet")
        if "solver_time_s" in events.column_names:
            plans = events.filter(pc.equal(events["kind"], "plan"))
            times.extend(plans.column("solver_time_s").to_pylist())
    return np.asarray([t for t in times if t is not None], dtype=float)


def markdown(out_dir: str | Path) -> str:
    """The Fig. 4, Fig. 5 and Fig. 6 tables for the runs found in ``out_dir``."""
    out = Path(out_dir)
    found = sorted(p.name for p in (out / "runs").iterdir() if p.is_dir())
    maps = {m: MAPS.get(m, m) for m in [*[m for m in MAPS if m in found], *found] if m in found}
    lines = [
        "| map | setting | explored at 300 / 600 / 900 steps [%] | per run at 900 "
        "| out of comm [steps] | plan time median / max [s] |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for m, name in maps.items():
        for setting, label in FIG4.items():
            runs = _runs(out, m, setting)
            if not runs:
                continue
            curves = [_explored(r) for r in runs]
            final = [100 * c[-1] for c in curves]
            ooc = [json.loads((r / "summary.json").read_text())["out_of_comm_mean_steps"]
                   for r in runs]  # fmt: skip
            pt = _plan_times(runs)
            lines.append(
                f"| {name} | {label} | {_at(curves, 300):.1f} / {_at(curves, 600):.1f} / "
                f"**{_pm(final)}** | {' '.join(f'{f:.0f}' for f in final)} | "
                f"{_pm(ooc, '{:.0f}')} | {np.median(pt):.3g} / {pt.max():.3g} |"
            )
    head = "| map | " + " | ".join(s.replace("theta", "theta = ") for s in FIG5) + " |"
    sep = "| --- " * (len(FIG5) + 1) + "|"
    fig5, fig6 = [head, sep], [head, sep]
    for m, name in maps.items():
        at300, at900, ooc = [], [], []
        for setting in FIG5:
            runs = _runs(out, m, setting)
            if not runs:
                at300.append("-"), at900.append("-"), ooc.append("-")
                continue
            curves = [_explored(r) for r in runs]
            at300.append(f"{_at(curves, 300):.1f}")
            at900.append(_pm([100 * c[-1] for c in curves]))
            occ = [json.loads((r / "summary.json").read_text())["out_of_comm_mean_steps"]
                   for r in runs]  # fmt: skip
            ooc.append(_pm(occ, "{:.0f}"))
        fig5.append(f"| {name}, explored at 300 steps [%] | " + " | ".join(at300) + " |")
        fig5.append(f"| {name}, explored at 900 steps [%] | " + " | ".join(at900) + " |")
        fig6.append(f"| {name} [steps per robot, of 900] | " + " | ".join(ooc) + " |")
    return "\n".join(
        ["### Fig. 4", "", *lines, "", "### Fig. 5", "", *fig5, "", "### Fig. 6", "", *fig6, ""]
    )


if __name__ == "__main__":
    print(markdown(sys.argv[1]))
