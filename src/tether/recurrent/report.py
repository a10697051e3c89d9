"""Re-make Figs. 4-6 of the recurrent-connectivity paper.

Banfi et al., Sec. VII-A: 12 robots, 900 steps, 5 runs per setting varying
the BS position, on the Cluttered (``grass``), Office (``offices``) and Open
(``open``) maps.

* Fig. 4: ILP against APX (``delta = 4``) with ``theta = 12``, (a) counting
  planning time in simulation steps, (b) instantaneous planning;
* Fig. 5: explored area known at the BS over time for ``theta`` in
  {1, 3, 6, 9, 12} and the Utility baseline (``r = 0.5``);
* Fig. 6: time robots spend out of communication with the BS;
* issue 13: theta = 1 against Utility with and without coordination, the relay
  binding both ways, and where the robots' time goes (``fig_time.png``); the
  tables with 95 % confidence intervals come from :mod:`.report_tables`.

This is a long experiment (benchmark-like), not a test::

    python -m tether.recurrent.report OUT_DIR --runs 5 --steps 900

The settings live in the paper campaign files ``scenarios/paper/recurrent_fig4.yaml``,
``recurrent_fig5_6.yaml`` and ``recurrent_fig5_6_utility.yaml``: each trial is a
combination of one of their sweeps (:mod:`.report_settings` says which), at the
report's map folder, team size and steps. Every run is a trial of
:mod:`tether.experiments` (a run folder under
``OUT_DIR/runs/<map>/<setting>/seed-<k>``, seed ``k`` placing the BS as
``tether run scenarios/recurrent_<map>.yaml --seed k`` does); finished runs
are reused when the report is run again, like every sweep. Figures go to ``OUT_DIR/fig4_<map>.png``,
``fig5.png`` and ``fig6.png``; final explored fractions (and out-of-comm
times, planning times) to ``OUT_DIR/report.json``.
"""

from __future__ import annotations

import json
import os
import sys
from pathlib import Path
from typing import Any

import numpy as np

from tether.config import Scenario, load_scenario, set_dotted, sweep_spec
from tether.experiments.executors import Trial
from tether.experiments.plan import trial_scenario as plan_trial_scenario
from tether.experiments.sweep import run_trials
from tether.recurrent.report_settings import (
    MAP_LABELS,
    Setting,
    display_name,
    run_dir,
    settings_table,
)
from tether.recurrent.report_tables import run_statistics
from tether.runfolder import machine, save_figure, write_json
from tether.viz.plots import pyplot

__all__ = ["combination", "make_report", "paper_scenario", "trial_scenario"]

MAPS_DIR = Path(__file__).resolve().parents[3] / ".." / "shared" / "maps"
#: the paper campaign files the settings come from (:mod:`.report_settings` names them)
PAPER_DIR = Path(__file__).resolve().parents[1] / "scenarios" / "paper"
_MISSING = object()


def paper_scenario(name: str) -> Scenario:
    """The paper campaign ``scenarios/paper/<name>.yaml`` (its sweep still in it)."""
    return load_scenario(PAPER_DIR / f"{name}.yaml")


def combination(base: Scenario, map_name: str, pick: dict[str, Any]) -> dict[str, Any]:
    """The combination of ``base``'s sweep for map ``map_name`` with the values of ``pick``.

    A map that is not on the file's ``world.params.path`` axis (a test map) takes the
    combination of the axis' first map; :func:`trial_scenario` replaces the path anyway.
    """
    combos = [c for c in sweep_spec(base).combinations()
              if all(c.get(k, _MISSING) == v for k, v in pick.items())]  # fmt: skip
    on_map = [c for c in combos if Path(c["world.params.path"]).stem == map_name]
    if not combos or len(on_map) > 1:
        found = "no" if not combos else "more than one"
        raise ValueError(f"{base.source}: {found} combination of the sweep has {pick}")
    return (on_map or combos)[0]


def trial_scenario(
    map_path: Path, setting: Setting, steps: int, n_robots: int, check: bool = False
) -> dict[str, Any]:
    """The scenario of one setting on one map: its paper file's combination, report-sized.

    The combination (:func:`combination`) applied by
    :func:`tether.experiments.plan.trial_scenario`, then the setting's variant values,
    the map file, the team size, the steps and ``check`` (recurrent strategy only);
    named ``recurrent-report-<map>`` with no description. The run seed is the trial's.
    """
    base = paper_scenario(setting.file)
    data = plan_trial_scenario(base, combination(base, map_path.stem, setting.pick)).model_dump(
        mode="json"
    )
    data["name"] = f"recurrent-report-{map_path.stem}"
    data["description"] = ""
    values = {**setting.variant, "world.params.path": str(map_path.resolve()),
              "team.n_robots": n_robots, "sim.max_steps": steps}  # fmt: skip
    if "check" in data["strategy"]["params"]:
        values["strategy.params.check"] = check
    for key, value in values.items():
        set_dotted(data, key, value)
    return data


def _curve(run_dir: Path) -> np.ndarray:
    import pyarrow.parquet as pq

    return pq.read_table(run_dir / "steps.parquet").column("explored_fraction").to_numpy()


def make_report(
    out_dir: str | Path,
    maps: tuple[str, ...] = ("grass", "offices", "open"),
    runs: int = 5,
    steps: int = 900,
    *,
    n_robots: int = 12,
    thetas: tuple[int, ...] = (1, 3, 6, 9, 12),
    settings: tuple[str, ...] | None = None,
    maps_dir: str | Path | None = None,
    workers: int | None = None,
    check: bool = False,
) -> dict[str, Any]:
    """Run the experiments of Figs. 4-6 and write figures and ``report.json``.

    Parameters
    ----------
    out_dir
        Output folder (created); finished runs found there are reused.
    maps
        Map names (files ``<maps_dir>/<name>.png``).
    runs, steps, n_robots
        Runs per setting (seeds ``0..runs-1`` fix the BS position, shared by
        all settings), steps per run, team size.
    thetas
        Replanning thresholds for Figs. 5-6.
    settings
        Subset of settings to run (default all: ``apx/ilp_t12_timed``,
        ``apx/ilp_t12_instant``, ``theta<k>``, ``theta1_assigned`` and
        ``theta1_frontiers`` (the relay binding both ways), ``utility_greedy`` and
        ``utility_none`` (Utility's coordination both ways); ``theta1`` and
        ``utility`` are the defaults' runs, see :mod:`.report_settings`). ``theta<k>``
        needs ``k`` on the ``strategy.params.theta`` axis of ``recurrent_fig5_6.yaml``.
    maps_dir
        Where the maps are (default ``../shared/maps`` next to the repository).
    workers
        Parallel processes (default: CPU count). Timed settings (Fig. 4a)
        measure planning wall time, so they are sensitive to machine load.
    check
        Check constraints (I)-(IV) on every plan (slower).
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    mdir = Path(maps_dir) if maps_dir is not None else MAPS_DIR
    all_settings = settings_table(tuple(thetas))
    chosen = {k: v for k, v in all_settings.items() if settings is None or k in settings}
    trials: list[Trial] = []
    keys: dict[str, list[tuple[str, str, int]]] = {}  # run folder -> (map, label, k)
    scenarios: dict[str, dict[str, Any]] = {}  # run folder -> its scenario
    for m in maps:
        map_path = mdir / f"{m}.png"
        if not map_path.exists():
            raise FileNotFoundError(f"{map_path}: map not found (give maps_dir)")
        for label, setting in chosen.items():
            data = trial_scenario(map_path, setting, steps, n_robots, check)
            for k in range(runs):
                folder = str(run_dir(out, m, label, k))
                if scenarios.setdefault(folder, data) != data:
                    raise ValueError(
                        f"{label}: its scenario is not that of {folder}, which it shares"
                    )
                if folder not in keys:  # labels of one scenario share their runs
                    trials.append(Trial(data, f"report:{m}/{label}", str(mdir), k, folder))
                keys.setdefault(folder, []).append((m, label, k))
    summaries: dict[tuple[str, str, int], dict[str, Any]] = {}
    outcome = run_trials(trials, executor="processes", workers=workers or os.cpu_count())
    if outcome.errors:
        raise RuntimeError("; ".join(outcome.errors[:3]))
    for folder, s in outcome.summaries.items():
        for key in keys[folder]:
            summaries[key] = s
            print(
                f"{key[0]:8s} {key[1]:16s} run{key[2]}: explored {s['final_explored_fraction']:.3f}"
                f" out-of-comm {s['out_of_comm_mean_steps']:.0f} wall {s['wall_time_s']:.1f}s",
                flush=True,
            )
    previous = out / "report.json"  # merge with earlier invocations (other settings/maps)
    old = json.loads(previous.read_text()) if previous.exists() else {}
    report: dict[str, Any] = {
        "runs": runs,
        "steps": steps,
        "n_robots": n_robots,
        "machine": machine(),
        "maps": {},
    }
    for m in maps:
        entry: dict[str, Any] = {}
        for label in chosen:
            ss = [summaries[(m, label, k)] for k in range(runs)]
            fin = [s["final_explored_fraction"] for s in ss]
            occ = [s["out_of_comm_mean_steps"] for s in ss]
            pt = [s.get("planning_time_mean_s", 0.0) for s in ss]
            ptmax = [s.get("planning_time_max_s", 0.0) for s in ss]
            entry[label] = {
                "final_explored": fin,
                "final_explored_mean": float(np.mean(fin)),
                "final_explored_std": float(np.std(fin)),
                "out_of_comm_mean_steps": float(np.mean(occ)),
                "out_of_comm_std_steps": float(np.std(occ)),
                "planning_time_mean_s": float(np.mean(pt)),
                "planning_time_max_s": float(np.max(ptmax)),
                "plans_mean": float(np.mean([s.get("plans", 0) for s in ss])),
                "constraint_violations": int(sum(s.get("constraint_violations", 0) for s in ss)),
                "wall_time_mean_s": float(np.mean([s["wall_time_s"] for s in ss])),
                **run_statistics(ss),
            }
        report["maps"][m] = {**old.get("maps", {}).get(m, {}), **entry}
    for m, entry in old.get("maps", {}).items():
        report["maps"].setdefault(m, entry)
    write_json(out / "report.json", report)
    _figures(out, maps, chosen, runs, thetas)
    return report


def _figures(
    out: Path,
    maps: tuple[str, ...],
    chosen: dict[str, Any],
    runs: int,
    thetas: tuple[int, ...],
) -> None:
    plt = pyplot()

    def mean_curve(m: str, label: str) -> tuple[np.ndarray, np.ndarray]:
        curves = np.array([_curve(run_dir(out, m, label, k)) for k in range(runs)])
        return 100 * curves.mean(axis=0), 100 * curves.std(axis=0)

    def band(ax: Any, m: str, label: str, name: str) -> None:
        mu, sd = mean_curve(m, label)
        t = np.arange(len(mu))
        ax.plot(t, mu, label=name)
        ax.fill_between(t, mu - sd, mu + sd, alpha=0.15)

    for m in maps:
        pairs = [("timed", "(a) with replanning time"), ("instant", "(b) instantaneous planning")]
        if not any(f"apx_t12_{p}" in chosen for p, _ in pairs):
            continue
        fig, axes = plt.subplots(1, 2, figsize=(10, 3.8), sharey=True)
        for ax, (mode, title) in zip(axes, pairs, strict=True):
            for method in ("ilp", "apx"):
                label = f"{method}_t12_{mode}"
                if label in chosen:
                    band(ax, m, label, method.upper())
            ax.set_title(f"{MAP_LABELS.get(m, m)}: {title}")
            ax.set_xlabel("step")
            ax.grid(alpha=0.3)
            if ax.lines:
                ax.legend()
        axes[0].set_ylabel("explored area [%]")
        fig.tight_layout()
        save_figure(fig, out / f"fig4_{m}.png")
        plt.close(fig)

    curves = [f"theta{th}" for th in thetas if f"theta{th}" in chosen]
    both = [u for u in ("utility_greedy", "utility_none") if u in chosen]
    curves += both or (["utility"] if "utility" in chosen else [])
    if curves:
        fig, axes = plt.subplots(1, len(maps), figsize=(5 * len(maps), 3.8), squeeze=False)
        for ax, m in zip(axes[0], maps, strict=True):
            for label in curves:
                band(ax, m, label, display_name(label))
            ax.set_title(MAP_LABELS.get(m, m))
            ax.set_xlabel("step")
            ax.set_ylabel("explored area [%]")
            ax.grid(alpha=0.3)
            ax.legend(fontsize=8)
        fig.tight_layout()
        save_figure(fig, out / "fig5.png")
        plt.close(fig)

        rep = json.loads((out / "report.json").read_text())
        fig, axes = plt.subplots(1, len(maps), figsize=(5 * len(maps), 3.5), squeeze=False)
        for ax, m in zip(axes[0], maps, strict=True):
            e = rep["maps"][m]
            names = [display_name(c).replace(" = ", "=").replace(" (", "\n(") for c in curves]
            mu = [e[c]["out_of_comm_mean_steps"] for c in curves]
            sd = [e[c]["out_of_comm_std_steps"] for c in curves]
            ax.bar(names, mu, yerr=sd, capsize=3)
            ax.set_title(MAP_LABELS.get(m, m))
            ax.set_ylabel("steps out of communication (mean per robot)")
            ax.grid(axis="y", alpha=0.3)
        fig.tight_layout()
        save_figure(fig, out / "fig6.png")
        plt.close(fig)
        _time_shares_figure(out, maps, curves, rep, plt)


def _time_shares_figure(out: Path, maps: tuple[str, ...], curves: list[str], rep: dict,
                        plt: Any) -> None:  # fmt: skip
    """Where the robots' time goes: stacked shares per setting and map (``fig_time.png``)."""
    states = ("moving", "relaying", "waiting", "returning")
    fig, axes = plt.subplots(1, len(maps), figsize=(5 * len(maps), 3.5), squeeze=False)
    for ax, m in zip(axes[0], maps, strict=True):
        e = rep["maps"][m]
        shown = [c for c in curves if e[c].get("time_moving_frac_mean") is not None]
        names = [display_name(c).replace(" = ", "=").replace(" (", "\n(") for c in shown]
        bottom = np.zeros(len(shown))
        for state in states:
            share = np.array([100 * e[c][f"time_{state}_frac_mean"] for c in shown])
            ax.bar(names, share, bottom=bottom, label=state)
            bottom += share
        ax.set_title(MAP_LABELS.get(m, m))
        ax.set_ylabel("robot time [%]")
        ax.set_ylim(0, 100)
    axes[0][0].legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    save_figure(fig, out / "fig_time.png")
    plt.close(fig)


def main(argv: list[str] | None = None) -> None:
    import argparse

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out_dir")
    ap.add_argument("--maps", nargs="+", default=["grass", "offices", "open"])
    ap.add_argument("--runs", type=int, default=5)
    ap.add_argument("--steps", type=int, default=900)
    ap.add_argument("--robots", type=int, default=12)
    ap.add_argument("--settings", nargs="*", default=None)
    ap.add_argument("--maps-dir", default=None)
    ap.add_argument("--workers", type=int, default=None)
    ap.add_argument("--check", action="store_true")
    a = ap.parse_args(argv)
    rep = make_report(
        a.out_dir,
        maps=tuple(a.maps),
        runs=a.runs,
        steps=a.steps,
        n_robots=a.robots,
        settings=tuple(a.settings) if a.settings else None,
        maps_dir=a.maps_dir,
        workers=a.workers,
        check=a.check,
    )
    for m, e in rep["maps"].items():
        for label, v in e.items():
            mu, sd = v["final_explored_mean"], v["final_explored_std"]
            print(f"{m:8s} {label:16s} final {mu:.3f} ± {sd:.3f}")


if __name__ == "__main__":
    main(sys.argv[1:])
