"""Markdown tables of the Figs. 4-6 re-make, computed from the campaigns' run folders.

:func:`markdown` makes the tables of ``docs/explanation/recurrent.md`` (``tether report --paper
recurrent`` writes them) for the runs of a :class:`RunIndex` (the run folders of each
map and setting, found in the campaigns' sweep folders by :mod:`tether.recurrent.report`):
explored area known at the BS after a third, two thirds and all of the steps (300, 600
and 900 in the paper's setting; mean over runs, and mean ± sample sd at the end), the
time robots spend out of communication (steps per robot), and per-plan solver times
(Figs. 4-6); theta = 1 against both Utility variants with 95 % confidence intervals
(Student t over the runs; differences by Welch's t), the relay binding both ways, and
where the robots' time goes. Tables whose runs are missing are left out.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pyarrow.compute as pc
import pyarrow.parquet as pq

from tether.recurrent.report_settings import display_name

__all__ = ["RunIndex", "ci95", "markdown", "run_statistics", "share_sum_error", "welch"]

FIG4 = {
    "apx_t12_timed": "APX, (a) planning time counted",
    "ilp_t12_timed": "ILP, (a) planning time counted",
    "apx_t12_instant": "APX, (b) instantaneous",
    "ilp_t12_instant": "ILP, (b) instantaneous",
}
FIG5 = ("theta1", "theta3", "theta6", "theta9", "theta12", "utility_greedy", "utility_none")
COMPARED = ("theta1", "utility_greedy", "utility_none")


@dataclass
class RunIndex:
    """The finished run folders of each map and setting, in seed order.

    Attributes
    ----------
    runs : dict
        ``(map key, setting label) -> [run folder, ...]`` (settings:
        :func:`tether.recurrent.report_settings.display_name` names them).
    maps : dict
        Map key -> its name in tables and figures, in display order.
    """

    runs: dict[tuple[str, str], list[Path]] = field(default_factory=dict)
    maps: dict[str, str] = field(default_factory=dict)

    def of(self, m: str, setting: str) -> list[Path]:
        """The run folders of ``setting`` on map ``m`` (empty if none)."""
        return self.runs.get((m, setting), [])

    def settings(self) -> list[str]:
        """Every setting with runs, in the order first found."""
        return list(dict.fromkeys(s for _, s in self.runs))

    def all_runs(self) -> list[Path]:
        return [r for runs in self.runs.values() for r in runs]

    def steps(self) -> int:
        """The longest run's steps (900 in the paper's setting)."""
        return max((json.loads((r / "summary.json").read_text())["steps"]
                    for r in self.all_runs()), default=0)  # fmt: skip


def _summaries(runs: list[Path]) -> list[dict]:
    return [json.loads((r / "summary.json").read_text()) for r in runs]


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


def welch(a: list[float], b: list[float]) -> tuple[float, float, float]:
    """Difference of means ``a - b``, the half-width of its 95 % CI and the p-value (Welch)."""
    from scipy.stats import t, ttest_ind

    a_, b_ = np.asarray(a, float), np.asarray(b, float)
    va, vb = a_.var(ddof=1) / len(a_), b_.var(ddof=1) / len(b_)
    se = np.sqrt(va + vb)
    diff = float(a_.mean() - b_.mean())
    if se == 0:
        return diff, 0.0, 0.0 if diff else 1.0
    dof = se**4 / (va**2 / (len(a_) - 1) + vb**2 / (len(b_) - 1))
    p = float(ttest_ind(a_, b_, equal_var=False).pvalue)
    return diff, float(t.ppf(0.975, dof) * se), p


def _mean(values: list) -> float | None:
    v = [x for x in values if x is not None]
    return float(np.mean(v)) if v else None


#: the summary keys (times to explore, where the time goes) of every setting's table
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


def markdown(index: RunIndex) -> str:
    """The Fig. 4, Fig. 5 and Fig. 6 tables (and the comparisons) for the runs of ``index``."""
    maps = index.maps
    end = index.steps()
    a, b = end // 3, 2 * end // 3
    lines = [
        f"| map | setting | explored at {a} / {b} / {end} steps [%] | per run at {end} "
        "| out of comm [steps] | plan time median / max [s] |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    for m, name in maps.items():
        for setting, label in FIG4.items():
            runs = index.of(m, setting)
            if not runs:
                continue
            curves = [_explored(r) for r in runs]
            final = [100 * c[-1] for c in curves]
            ooc = [json.loads((r / "summary.json").read_text())["out_of_comm_mean_steps"]
                   for r in runs]  # fmt: skip
            pt = _plan_times(runs)
            lines.append(
                f"| {name} | {label} | {_at(curves, a):.1f} / {_at(curves, b):.1f} / "
                f"**{_pm(final)}** | {' '.join(f'{f:.0f}' for f in final)} | "
                f"{_pm(ooc, '{:.0f}')} | {np.median(pt):.3g} / {pt.max():.3g} |"
            )
    head = "| map | " + " | ".join(display_name(s) for s in FIG5) + " |"
    sep = "| --- " * (len(FIG5) + 1) + "|"
    fig5, fig6 = [head, sep], [head, sep]
    for m, name in maps.items():
        at300, at900, ooc = [], [], []
        for setting in FIG5:
            runs = index.of(m, setting)
            if not runs:
                at300.append("-"), at900.append("-"), ooc.append("-")
                continue
            curves = [_explored(r) for r in runs]
            at300.append(f"{_at(curves, a):.1f}")
            at900.append(_pm([100 * c[-1] for c in curves]))
            occ = [json.loads((r / "summary.json").read_text())["out_of_comm_mean_steps"]
                   for r in runs]  # fmt: skip
            ooc.append(_pm(occ, "{:.0f}"))
        fig5.append(f"| {name}, explored at {a} steps [%] | " + " | ".join(at300) + " |")
        fig5.append(f"| {name}, explored at {end} steps [%] | " + " | ".join(at900) + " |")
        fig6.append(f"| {name} [steps per robot, of {end}] | " + " | ".join(ooc) + " |")
    fig5 += _plans_row(index, maps) + _anova(index, maps)
    parts = ["### Fig. 4", "", *lines, "", "### Fig. 5", "", *fig5, "", "### Fig. 6", "", *fig6, ""]
    parts += _comparison(index, maps) + _binding(index, maps) + _shares(index, maps)
    return "\n".join(parts).replace("at 900 steps", f"at {end} steps")


def _plans_row(index: RunIndex, maps: dict[str, str]) -> list[str]:
    """Plans per run and mean plan time of every theta: range over runs and maps."""
    cells = []
    for setting in FIG5:
        ss = [s for m in maps for s in _summaries(index.of(m, setting))]
        if setting.startswith("utility") or not ss:
            cells.append("-")
            continue
        n = [s.get("plans", 0) for s in ss]
        t = [s.get("planning_time_mean_s", 0.0) for s in ss]
        cells.append(f"{min(n)}-{max(n)} / {min(t):.2f}-{max(t):.2f}")
    label = "APX plans per run / mean plan time [s] (range over runs and maps)"
    return [f"| {label} | " + " | ".join(cells) + " |"]


def _anova(index: RunIndex, maps: dict[str, str]) -> list[str]:
    """theta = 1 against theta = 12 at the end: one-way ANOVA p-value per map."""
    from scipy.stats import f_oneway

    found = []
    for m, name in maps.items():
        a, b = (_summaries(index.of(m, s)) for s in ("theta1", "theta12"))
        if len(a) > 1 and len(b) > 1:
            fa, fb = ([100 * s["final_explored_fraction"] for s in x] for x in (a, b))
            diff = np.mean(fa) - np.mean(fb)
            found.append(f"{name} {diff:+.1f} points, p = {f_oneway(fa, fb).pvalue:.2g}")
    if not found:
        return []
    return ["", "theta = 1 against theta = 12 at the end (one-way ANOVA): " + "; ".join(found)]


def _ci(values: list[float], fmt: str = "{:.1f}") -> str:
    mu, half = ci95(values)
    if mu is None:
        return "-"
    if half is None:
        return fmt.format(mu)
    return f"{fmt.format(mu)} [{fmt.format(mu - half)}, {fmt.format(mu + half)}]"


def _time_to(ss: list[dict], key: str) -> str:
    hit = [s[key] for s in ss if s.get(key) is not None]
    if not hit:
        return "never"
    return f"{np.mean(hit):.0f}" + ("" if len(hit) == len(ss) else f" ({len(hit)}/{len(ss)})")


def _comparison(index: RunIndex, maps: dict[str, str]) -> list[str]:
    """theta = 1 against Utility (greedy, none): CIs of the means and of the differences."""
    lines = [
        "### theta = 1 against Utility (95 % confidence intervals)",
        "",
        "| map | strategy | explored at 900 steps [%] | per run | time to 50 / 75 / 90 % [s] "
        "| out of comm [steps per robot] | episodes per robot / longest [steps] |",
        "| --- | --- | --- | --- | --- | --- | --- |",
    ]
    diffs = ["", "| map | difference | explored at 900 steps [points] | p (Welch) |",
             "| --- | --- | --- | --- |"]  # fmt: skip
    found = False
    for m, name in maps.items():
        finals: dict[str, list[float]] = {}
        for setting in COMPARED:
            ss = _summaries(index.of(m, setting))
            if not ss:
                continue
            found = True
            fin = [100 * s["final_explored_fraction"] for s in ss]
            finals[setting] = fin
            ooc = [s["out_of_comm_mean_steps"] for s in ss]
            eps = np.mean([s.get("out_of_comm_episodes", np.nan) for s in ss]) / ss[0]["n_robots"]
            longest = np.mean([s.get("out_of_comm_longest_steps", np.nan) for s in ss])
            tt = " / ".join(_time_to(ss, f"time_to_{p}pct_s") for p in (50, 75, 90))
            lines.append(
                f"| {name} | {display_name(setting)} | **{_ci(fin)}** | "
                f"{' '.join(f'{f:.0f}' for f in fin)} | {tt} | {_ci(ooc, '{:.0f}')} | "
                f"{eps:.1f} / {longest:.0f} |"
            )
        for other in COMPARED[1:]:
            if "theta1" in finals and other in finals and len(finals[other]) > 1:
                d, half, p = welch(finals["theta1"], finals[other])
                ci = f"{d:+.1f} [{d - half:+.1f}, {d + half:+.1f}]"
                diffs.append(f"| {name} | θ = 1 − {display_name(other)} | {ci} | {p:.2g} |")
    return [*lines, *diffs, ""] if found else []


def _binding(index: RunIndex, maps: dict[str, str]) -> list[str]:
    """theta = 1 with P_f for every assigned robot against the paper's rule."""
    lines = [
        "### Relay binding at theta = 1 (95 % confidence intervals)",
        "",
        "| map | P_f bound for | explored at 900 steps [%] | out of comm [steps per robot] "
        "| longest episode [steps] | relaying / waiting [% of robot time] |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    found = False
    paired: list[float] = []  # assigned - frontiers, run by run (same seed, same BS)
    for m, name in maps.items():
        finals = {}
        for rule in ("assigned", "frontiers"):
            ss = _summaries(index.of(m, f"theta1_{rule}"))
            if not ss:
                continue
            found = True
            finals[rule] = [100 * s["final_explored_fraction"] for s in ss]
            ooc = [s["out_of_comm_mean_steps"] for s in ss]
            longest = [s.get("out_of_comm_longest_steps") for s in ss]
            rel = 100 * np.mean([s.get("time_relaying_frac", np.nan) for s in ss])
            wait = 100 * np.mean([s.get("time_waiting_frac", np.nan) for s in ss])
            who = "every assigned robot" if rule == "assigned" else "(fake) frontiers (paper)"
            lines.append(
                f"| {name} | {who} | **{_ci(finals[rule])}** | {_ci(ooc, '{:.0f}')} | "
                f"{_ci(longest, '{:.0f}')} | {rel:.0f} / {wait:.0f} |"
            )
        if len(finals) == 2 and min(len(v) for v in finals.values()) > 1:
            d, half, p = welch(finals["assigned"], finals["frontiers"])
            lines.append(f"| {name} | difference | {d:+.1f} [{d - half:+.1f}, {d + half:+.1f}] "
                         f"(p = {p:.2g}) | | | |")  # fmt: skip
        if len(finals) == 2 and len(finals["assigned"]) == len(finals["frontiers"]):
            paired += [a - b for a, b in zip(finals["assigned"], finals["frontiers"], strict=True)]
    if len(paired) > 1:
        from scipy.stats import ttest_1samp

        mu, half = ci95(paired)
        p = float(ttest_1samp(paired, 0.0).pvalue)
        cell = f"{mu:+.1f} [{mu - half:+.1f}, {mu + half:+.1f}] (p = {p:.2g})"
        lines.append(f"| all maps | paired by BS position ({len(paired)} pairs) | {cell} | | | |")
    return [*lines, ""] if found else []


def _shares(index: RunIndex, maps: dict[str, str]) -> list[str]:
    """Where the robots' time goes: moving / relaying / waiting / returning."""
    lines = [
        "### Where the robots' time goes [% of robot time, mean over runs]",
        "",
        "| map | strategy | moving | relaying | waiting | returning |",
        "| --- | --- | --- | --- | --- | --- |",
    ]
    found = False
    for m, name in maps.items():
        for setting in ("theta1", "theta12", "utility_greedy", "utility_none"):
            ss = _summaries(index.of(m, setting))
            if not ss or "time_moving_frac" not in ss[0]:
                continue
            found = True
            cells = [f"{100 * np.mean([s[f'time_{k}_frac'] for s in ss]):.0f}"
                     for k in ("moving", "relaying", "waiting", "returning")]  # fmt: skip
            lines.append(f"| {name} | {display_name(setting)} | " + " | ".join(cells) + " |")
    if not found:
        return []
    n, err = share_sum_error(index)
    lines += ["", f"The four shares sum to 1 on every one of the {n} runs with them "
              f"(largest deviation {err:.1e})."]  # fmt: skip
    return [*lines, ""]


def share_sum_error(index: RunIndex) -> tuple[int, float]:
    """Runs of ``index`` that report time shares, and the largest ``|sum - 1|``."""
    errors = []
    for run in index.all_runs():
        s = json.loads((run / "summary.json").read_text())
        if all(k in s for k in SHARES):
            errors.append(abs(sum(s[k] for k in SHARES) - 1.0))
    return len(errors), max(errors, default=0.0)
