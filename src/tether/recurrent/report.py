"""``tether report --paper recurrent``: Figs. 4-6 of the recurrent-connectivity paper.

Banfi et al., Sec. VII-A: 12 robots, 900 steps, 5 runs per setting varying the BS
position, on the Cluttered (``grass``), Office (``offices``) and Open (``open``) maps.
The runs are the trials of four paper campaigns, each run by ``tether sweep``::

    tether sweep paper/recurrent_fig4 --out runs/fig4              # Fig. 4: ILP against APX
    tether sweep paper/recurrent_fig5_6 --out runs/fig5_6          # Figs. 5-6: theta
    tether sweep paper/recurrent_fig5_6_utility --out runs/utility # the Utility baseline
    tether sweep paper/recurrent_relay_binding --out runs/relay    # relay binding, theta = 1
    tether report runs/fig4 runs/fig5_6 runs/utility runs/relay --paper recurrent --out runs/paper

Any subset of the folders (at the full or the quick size) makes the figures and tables
their runs allow. The report writes, into ``--out`` (default: the first folder):

* ``figures/recurrent_fig4_<map>.png``: explored area over time, ILP against APX with
  theta = 12, (a) counting planning time in simulation steps, (b) instantaneous;
* ``figures/recurrent_fig5.png``: explored area known at the BS over time for each
  theta and Utility (both coordinations); ``recurrent_fig6.png``: time out of
  communication; ``recurrent_fig_time.png``: where the robots' time goes;
* ``recurrent_paper.md``: the tables of ``docs/explanation/recurrent.md``
  (:mod:`tether.recurrent.report_tables`) and the figures;
* ``recurrent_paper.json``: per map and setting, final explored fractions, times out of
  communication, plan counts and times, with 95 % confidence intervals.

A run on a stand-in map (``world.params.stand_in_path``, recorded in its
``summary.json``) is shown as its own map, named "(stand-in)".
"""

from __future__ import annotations

import datetime as dt
import json
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.parquet as pq

from tether.errors import TetherError
from tether.experiments.results import SweepResults, load_results
from tether.recurrent.report_settings import CAMPAIGNS, MAP_LABELS, display_name, setting_label
from tether.recurrent.report_tables import RunIndex, markdown, run_statistics
from tether.runfolder import atomic_write, machine, save_figure, write_json
from tether.viz.plots import pyplot

__all__ = ["PAPERS", "campaign_kind", "index_runs", "write_paper_report"]

#: the papers ``tether report --paper`` knows
PAPERS = ("recurrent",)
REPORT, NUMBERS = "recurrent_paper.md", "recurrent_paper.json"
_TITLE = "# The recurrent-connectivity paper's Figs. 4-6"


def campaign_kind(results: SweepResults) -> str:
    """Which recurrent campaign a sweep folder holds (a key of ``CAMPAIGNS``).

    Told by what the sweep varies, so a renamed or quick-size copy is recognised too.
    """
    strategy = results.scenario.get("strategy", {}).get("name")
    axes = set(results.axes)
    if strategy == "utility":
        return "utility"
    if strategy == "recurrent" and "strategy.params.method" in axes:
        return "fig4"
    if strategy == "recurrent" and "strategy.params.relay_binding" in axes:
        return "relay"
    if strategy == "recurrent" and "strategy.params.theta" in axes:
        return "fig5_6"
    raise TetherError(
        f"{results.folder}: not a sweep of one of the recurrent paper's campaigns "
        f"({', '.join(CAMPAIGNS.values())}); give their sweep folders"
    )


def _run_folder(results: SweepResults, row: dict[str, Any]) -> Path:
    path = Path(row["run_dir"])
    return path if path.is_dir() else results.folder / row["trial_id"]  # a moved sweep


def _map_of(results: SweepResults, row: dict[str, Any], run: Path) -> tuple[str, str]:
    """The map key and name of a trial: the map file's stem, "(stand-in)" if it ran on one."""
    given = row.get("param:world.params.path")
    if given is None:
        given = results.scenario.get("world", {}).get("params", {}).get("path", "map")
    stem = Path(str(given)).stem
    name = MAP_LABELS.get(stem, stem)
    try:
        kept = json.loads((run / "summary.json").read_text()).get("scene_files") or []
    except (OSError, ValueError):
        kept = []
    stand_in = next((f["stand_in"] for f in kept if f.get("stand_in")), None)
    if stand_in is not None:
        return f"{stem}-stand-in", f"{name} (stand-in {Path(stand_in).name})"
    return stem, name


def index_runs(sweep_dirs: list[Path]) -> tuple[RunIndex, dict[str, Path]]:
    """The finished runs of the campaigns' sweep folders by map and setting.

    Returns
    -------
    RunIndex
        Runs in seed order; maps in the paper's order (Cluttered, Office, Open) first.
    dict
        Campaign kind -> its sweep folder.

    Raises
    ------
    TetherError
        A folder that is not a sweep of a recurrent campaign, or two of one campaign.
    """
    found: dict[tuple[str, str], list[tuple[int, Path]]] = {}
    names: dict[str, str] = {}
    folders: dict[str, Path] = {}
    for folder in sweep_dirs:
        results = load_results(folder)
        kind = campaign_kind(results)
        if kind in folders:
            raise TetherError(
                f"{folder}: a second sweep of {CAMPAIGNS[kind]} (the first: {folders[kind]}); "
                "give one folder per campaign"
            )
        folders[kind] = results.folder
        defaults = results.scenario.get("strategy", {}).get("params", {})
        for row in results.done:
            values = {k.rsplit(".", 1)[-1]: v for k, v in row.items()
                      if k.startswith("param:strategy.params.")}  # fmt: skip
            label = setting_label(kind, {**defaults, **values})
            run = _run_folder(results, row)
            key, name = _map_of(results, row, run)
            names.setdefault(key, name)
            found.setdefault((key, label), []).append((int(row["seed"]), run))
    order = [k for m in MAP_LABELS for k in (m, f"{m}-stand-in") if k in names]
    order += sorted(k for k in names if k not in order)
    runs = {key: [r for _, r in sorted(v)] for key, v in found.items()}
    return RunIndex(runs, {k: names[k] for k in order}), folders


def _curves(runs: list[Path]) -> np.ndarray:
    """Explored fraction per step, one row per run (NaN after a shorter run's end)."""
    rows = [pq.read_table(r / "steps.parquet", columns=["explored_fraction"]).column(0).to_numpy()
            for r in runs]  # fmt: skip
    out = np.full((len(rows), max(len(r) for r in rows)), np.nan)
    for k, row in enumerate(rows):
        out[k, : len(row)] = row
    return out


def _band(ax: Any, runs: list[Path], name: str) -> None:
    curves = 100 * _curves(runs)
    mu, sd = np.nanmean(curves, axis=0), np.nanstd(curves, axis=0)
    t = np.arange(len(mu))
    ax.plot(t, mu, label=f"{name} ({len(runs)} runs)")
    ax.fill_between(t, mu - sd, mu + sd, alpha=0.15)


def _fig4(index: RunIndex, figures: Path) -> list[Path]:
    plt, out = pyplot(), []
    pairs = [("timed", "(a) with replanning time"), ("instant", "(b) instantaneous planning")]
    for m, map_name in index.maps.items():
        if not any(index.of(m, f"{meth}_t12_{p}") for meth in ("apx", "ilp") for p, _ in pairs):
            continue
        fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), sharey=True)
        for ax, (mode, title) in zip(axes, pairs, strict=True):
            for method in ("ilp", "apx"):
                if runs := index.of(m, f"{method}_t12_{mode}"):
                    _band(ax, runs, method.upper())
            ax.set_title(f"{map_name}: {title}", fontsize=9)
            ax.set_xlabel("step")
            ax.grid(alpha=0.3)
            if ax.lines:
                ax.legend(fontsize=8)
        axes[0].set_ylabel("explored area [%] (mean ± sd)")
        fig.tight_layout()
        out.append(save_figure(fig, figures / f"recurrent_fig4_{m}.png"))
    return out


def _fig5_6(index: RunIndex, figures: Path) -> list[Path]:
    settings = index.settings()
    thetas = sorted((s for s in settings if s.startswith("theta") and "_" not in s),
                    key=lambda s: int(s[5:]))  # fmt: skip
    curves = thetas + [u for u in ("utility_greedy", "utility_none") if u in settings]
    maps = [m for m in index.maps if any(index.of(m, c) for c in curves)]
    if not curves or not maps:
        return []
    plt, out = pyplot(), []
    fig, axes = plt.subplots(1, len(maps), figsize=(5 * len(maps), 3.8), squeeze=False)
    for ax, m in zip(axes[0], maps, strict=True):
        for label in curves:
            if runs := index.of(m, label):
                _band(ax, runs, display_name(label))
        ax.set_title(index.maps[m], fontsize=9)
        ax.set_xlabel("step")
        ax.set_ylabel("explored area [%] (mean ± sd)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    out.append(save_figure(fig, figures / "recurrent_fig5.png"))

    def summaries(m: str, label: str) -> list[dict[str, Any]]:
        return [json.loads((r / "summary.json").read_text()) for r in index.of(m, label)]

    fig, axes = plt.subplots(1, len(maps), figsize=(5 * len(maps), 3.5), squeeze=False)
    tshare, taxes = plt.subplots(1, len(maps), figsize=(5 * len(maps), 3.5), squeeze=False)
    for ax, tax, m in zip(axes[0], taxes[0], maps, strict=True):
        shown = [c for c in curves if index.of(m, c)]
        names = [display_name(c).replace(" = ", "=").replace(" (", "\n(") for c in shown]
        occ = [[s["out_of_comm_mean_steps"] for s in summaries(m, c)] for c in shown]
        ax.bar(names, [np.mean(o) for o in occ], yerr=[np.std(o) for o in occ], capsize=3)
        ax.set_title(index.maps[m], fontsize=9)
        ax.set_ylabel("steps out of communication\n(mean per robot, ± sd over runs)")
        ax.grid(axis="y", alpha=0.3)
        bottom = np.zeros(len(shown))
        for state in ("moving", "relaying", "waiting", "returning"):
            share = [100 * np.mean([s.get(f"time_{state}_frac", np.nan) for s in summaries(m, c)])
                     for c in shown]  # fmt: skip
            tax.bar(names, share, bottom=bottom, label=state)
            bottom += np.nan_to_num(share)
        tax.set_title(index.maps[m], fontsize=9)
        tax.set_ylabel("robot time [%]")
        tax.set_ylim(0, 100)
    taxes[0][0].legend(fontsize=8, loc="lower left")
    for figure, name in ((fig, "recurrent_fig6.png"), (tshare, "recurrent_fig_time.png")):
        figure.tight_layout()
        out.append(save_figure(figure, figures / name))
    return out


def _numbers(index: RunIndex, folders: dict[str, Path]) -> dict[str, Any]:
    report: dict[str, Any] = {
        "campaigns": {k: str(v) for k, v in folders.items()},
        "machine": machine(),
        "maps": {},
    }
    for m, name in index.maps.items():
        entry: dict[str, Any] = {}
        for label in index.settings():
            ss = [json.loads((r / "summary.json").read_text()) for r in index.of(m, label)]
            if not ss:
                continue
            fin = [s["final_explored_fraction"] for s in ss]
            occ = [s["out_of_comm_mean_steps"] for s in ss]
            entry[label] = {
                "runs": len(ss),
                "steps": ss[0]["steps"],
                "seeds": [s["seed"] for s in ss],
                "final_explored": fin,
                "final_explored_mean": float(np.mean(fin)),
                "final_explored_std": float(np.std(fin)),
                "out_of_comm_mean_steps": float(np.mean(occ)),
                "out_of_comm_std_steps": float(np.std(occ)),
                "planning_time_mean_s": float(
                    np.mean([s.get("planning_time_mean_s", 0.0) for s in ss])
                ),  # fmt: skip
                "planning_time_max_s": float(max(s.get("planning_time_max_s", 0.0) for s in ss)),
                "plans_mean": float(np.mean([s.get("plans", 0) for s in ss])),
                "constraint_violations": int(sum(s.get("constraint_violations", 0) for s in ss)),
                "wall_time_mean_s": float(np.mean([s["wall_time_s"] for s in ss])),
                **run_statistics(ss),
            }
        report["maps"][name] = entry
    return report


def write_paper_report(
    paper: str,
    sweep_dirs: list[str | Path],
    out_dir: str | Path | None = None,
    command: str | None = None,
) -> Path:
    """Write a paper's figures, tables and numbers from its campaigns' sweep folders.

    Parameters
    ----------
    paper
        ``"recurrent"`` (:data:`PAPERS`).
    sweep_dirs
        Sweep folders of the paper's campaigns (any subset, one per campaign).
    out_dir
        Where to write (default: the first sweep folder).

    Returns
    -------
    Path
        ``<out_dir>/recurrent_paper.md``.
    """
    if paper not in PAPERS:
        raise TetherError(f"--paper {paper}: unknown paper; expected one of: {', '.join(PAPERS)}")
    if not sweep_dirs:
        raise TetherError("--paper recurrent: give the sweep folders of its campaigns")
    index, folders = index_runs([Path(d) for d in sweep_dirs])
    if not index.runs:
        raise TetherError(
            f"{', '.join(map(str, sweep_dirs))}: no finished trial; run the sweeps first"
        )
    out = Path(out_dir) if out_dir is not None else Path(sweep_dirs[0])
    _refuse_foreign(out)
    figures = out / "figures"
    figures.mkdir(parents=True, exist_ok=True)
    drawn = _fig4(index, figures) + _fig5_6(index, figures)
    write_json(out / NUMBERS, _numbers(index, folders))
    when = dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds")
    lines = [
        _TITLE,
        "",
        f"Made by `{command or 'tether report --paper recurrent'}` on {when} from "
        + ", ".join(f"`{folders[k]}` ({CAMPAIGNS[k]})" for k in folders)
        + f"; numbers in `{NUMBERS}`.",
        "",
        *[f"![{p.stem}](figures/{p.name})\n" for p in drawn],
        markdown(index),
    ]
    text = "\n".join(lines)
    atomic_write(out / REPORT, lambda tmp: Path(tmp).write_text(text))
    return out / REPORT


def _refuse_foreign(out: Path) -> None:
    """Refuse to replace a ``recurrent_paper.md`` or ``.json`` that this report did not write."""
    report, numbers = out / REPORT, out / NUMBERS
    ours = True
    if report.is_file():
        with open(report, encoding="utf-8", errors="replace") as fh:
            ours = fh.readline().startswith(_TITLE)
    if ours and numbers.is_file():
        try:
            ours = "campaigns" in json.loads(numbers.read_text())
        except (OSError, ValueError, TypeError):
            ours = False
    if not ours:
        raise TetherError(
            f"{out}: holds a {REPORT} or {NUMBERS} that tether did not write; give another "
            "--out (nothing was written)"
        )


if __name__ == "__main__":  # not a command: say which one makes the report
    import sys

    print(
        "error: the recurrent paper's report is `tether report SWEEP_DIR ... --paper recurrent` "
        "over the sweeps of paper/recurrent_* (see `tether report --help`)",
        file=sys.stderr,
    )
    sys.exit(2)
