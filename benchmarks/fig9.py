"""Fig. 9 of the continuous-connectivity paper, re-made: the multi-target campaign.

Runs (resumably) the sweeps ``scenarios/paper/continuous_fig9_<scene>.yaml`` (team
sizes x target configurations = run seeds) and draws the percentiles (10, 25, 50, 75,
90) of the paper's four metrics against the team size, one column per scene:
completion time, mean travelled distance of the explorers, largest distance between
two explorers, and the mean weighted lambda2 over time. Writes
``benchmarks/results/fig9.json`` (percentiles, trend statistics, completeness, the
machine and wall times) and ``docs/figures/multi_target_fig9.png``.

    python benchmarks/fig9.py --seeds 100                  # the paper's 1,800 trials
    python benchmarks/fig9.py --seeds 5 --sizes 10 20 35   # a quick version
    python benchmarks/fig9.py --no-run                     # figure from every finished trial
    python benchmarks/fig9.py --first-seed 12 --seeds 6    # configurations 12-17 only

Trends (in the JSON): the ratio of the median completion time at the largest team to
the smallest, Spearman's rank correlation of each metric with N over all trials (with
its p-value, scipy.stats), and the share of trials that reached every target.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
from scipy import stats

from tether.config import load_scenario
from tether.experiments.sweep import run_sweep
from tether.runfolder import machine
from tether.viz.plots import pyplot

ROOT = Path(__file__).resolve().parents[1]
SCENES = ("empty", "town", "office")
METRICS = (
    ("completion_time_s", "completion time [s]"),
    ("mean_explorer_distance_m", "mean travelled distance\nof the explorers [m]"),
    ("max_explorer_stretch_m", "max distance between\ntwo explorers [m]"),
    ("mean_lambda2_weighted", "mean lambda2"),
)
PERCENTILES = (10, 25, 50, 75, 90)


def sweep_file(scene: str) -> Path:
    return ROOT / "src" / "tether" / "scenarios" / "paper" / f"continuous_fig9_{scene}.yaml"


def run_column(
    scene: str, out: Path, seeds: int | list[int], sizes: list[int], workers: int
) -> float:
    sc = load_scenario(sweep_file(scene))
    sc.sweep = {"team.n_robots": sizes}
    tic = time.perf_counter()
    run_sweep(sc, out, seeds=seeds, executor="processes" if workers > 1 else "serial",
              workers=workers, progress=lambda m: print(f"{scene}: {m}", flush=True))  # fmt: skip
    return time.perf_counter() - tic


def load_rows(out: Path, sizes: list[int], seeds: int | None) -> list[dict]:
    """The trials of one scene's table (of the first ``seeds`` seeds; all if None)."""
    rows = pq.read_table(out / "sweep.parquet").to_pylist()
    return [r for r in rows if r["param:team.n_robots"] in sizes
            and (seeds is None or r["seed"] < seeds)]  # fmt: skip


def failure(row: dict) -> str:
    """Why a trial is not a success of the mission (empty if it is): every target
    reached, and the controller's success: the controller alone kept the weighted lambda2
    above lambda2_min = 0 (no connectivity loss, collision or clearance breach) at every
    sub-step with the guard only watching; no collision between recorded steps; every
    robot within its speed bound."""
    why = []
    if row["targets_reached"] != row["targets_total"]:
        why.append(f"{row['targets_reached']}/{row['targets_total']} targets "
                   f"({row['targets_dropped']} dropped)")  # fmt: skip
    if row.get("controller_success") is not True:
        parts = [
            f"{row.get(k)} {k.replace('_', ' ')}"
            for k in ("safe_set_exits", "guard_interventions", "tolerance_misses")
            if row.get(k)
        ]
        flag = row.get("controller_success")
        why.append("controller: " + (", ".join(parts) or f"success {flag}"))
    if row["collisions"]:
        why.append(f"{row['collisions']} collisions")
    if (row.get("max_speed_mps") or 0.0) > (row.get("speed_bound_mps") or np.inf):
        why.append(f"speed {row['max_speed_mps']:.3g} m/s above {row['speed_bound_mps']}")
    return "; ".join(why)


def _metric(row: dict, key: str) -> float:
    """A trial's value of ``key`` (NaN if missing); the completion time only of a trial
    that reached every target (``summary.json`` has none where a target was dropped or is
    pending)."""
    if key == "completion_time_s" and row["targets_reached"] != row["targets_total"]:
        return np.nan
    return np.nan if row.get(key) is None else float(row[key])


def _column(rows: list[dict], key: str) -> np.ndarray:
    return np.array([_metric(r, key) for r in rows])


def dynamics(rows: list[dict]) -> dict:
    """What the integrator, the robot model and the guard did over the trials."""
    out: dict = {"controller_successes": int(sum(r.get("controller_success") is True
                                                 for r in rows))}  # fmt: skip
    for key in ("safe_set_exits", "guard_interventions", "tolerance_misses", "stalls",
                "anchor_outside_steps"):  # fmt: skip
        vals = _column(rows, key)
        out[f"trials_with_{key}"] = int(np.sum(vals > 0))
    for key in ("max_speed_mps", "max_accel_mps2", "energy_added_j", "speed_limit_work_j",
                "longest_prime_vacancy_steps", "reference_filter_max_deviation_m",
                "reference_filter_max_accel_mps2"):  # fmt: skip
        vals = _column(rows, key)
        if np.isfinite(vals).any():
            out[key] = {"median": float(np.nanmedian(vals)), "max": float(np.nanmax(vals))}
    # Sec. 3.3's bound on a vacancy of the prime role after the start-up: N - 1 steps
    over = [r for r in rows if (r.get("longest_prime_vacancy_steps") or 0)
            > r["param:team.n_robots"] - 1]  # fmt: skip
    out["vacancy_above_bound"] = [
        {"n_robots": r["param:team.n_robots"], "seed": r["seed"],
         "steps": r["longest_prime_vacancy_steps"]} for r in over
    ]  # fmt: skip
    sub, rej = _column(rows, "substeps"), _column(rows, "rejected_substeps")
    out["rejected_share"] = float(np.nansum(rej) / max(np.nansum(sub + rej), 1))
    out["substeps_per_step"] = float(np.nansum(sub) / max(np.nansum(_column(rows, "steps")), 1))
    return out


def summarise(rows: list[dict], sizes: list[int]) -> dict:
    out: dict = {"trials": len(rows)}
    failed = [failure(r) for r in rows]
    out["complete_share"] = float(np.mean([not f for f in failed])) if rows else None
    out["min_lambda2_weighted"] = min((r["min_lambda2_weighted"] for r in rows), default=None)
    out["collisions"] = int(sum(r["collisions"] for r in rows))
    for key in ("targets_total", "targets_reached", "targets_dropped"):
        out[key] = int(sum(r[key] or 0 for r in rows))
    out["trials_helped"] = int(sum(1 for r in rows if (r.get("help_requests") or 0) > 0))
    out["dynamics"] = dynamics(rows)
    low = min(rows, key=lambda r: r["min_lambda2_weighted"], default=None)
    if low is not None:
        out["min_lambda2_trial"] = {"n_robots": low["param:team.n_robots"], "seed": low["seed"]}
    out["failed_trials"] = [
        {"n_robots": r["param:team.n_robots"], "seed": r["seed"], "why": f}
        for r, f in zip(rows, failed, strict=True) if f
    ]  # fmt: skip
    n = np.array([r["param:team.n_robots"] for r in rows])
    wall = np.array([r["wall_time_s"] or np.nan for r in rows], dtype=float)
    sim = np.array([r["sim_time_s"] or np.nan for r in rows], dtype=float)
    cpu = _column(rows, "cpu_time_s")
    out["trial_wall_s_total"] = float(np.nansum(wall))  # CPU-bound: one core per trial
    out["trial_cpu_s_total"] = float(np.nansum(cpu))
    out["sim_over_wall_median"] = {str(size): float(np.nanmedian(sim[n == size] / wall[n == size]))
                                   for size in sizes if (n == size).any()}  # fmt: skip
    for key, _ in METRICS:
        vals = _column(rows, key)
        per = {}
        for size in sizes:
            v = vals[(n == size) & np.isfinite(vals)]
            per[str(size)] = [float(np.percentile(v, p)) for p in PERCENTILES] if len(v) else None
        ok = np.isfinite(vals)
        rho, p = stats.spearmanr(n[ok], vals[ok]) if ok.sum() > 2 else (np.nan, np.nan)
        out[key] = {"percentiles": per, "spearman_rho": float(rho), "spearman_p": float(p)}
    med = out["completion_time_s"]["percentiles"]
    if med.get(str(sizes[0])) and med.get(str(sizes[-1])):
        out["completion_median_ratio_last_first"] = med[str(sizes[-1])][2] / med[str(sizes[0])][2]
    return out


def _over_bound(trials: list[dict]) -> str:
    """``"k trials"`` and which, e.g. ``"1 trials (N = 15, seed 13: 25 steps)"``."""
    which = ", ".join(f"N = {t['n_robots']}, seed {t['seed']}: {t['steps']} steps" for t in trials)
    return f"{len(trials)} trials" + (f" ({which})" if which else "")


def _mm(dyn: dict, key: str, unit: str) -> str:
    v = dyn.get(key)
    return f"median {v['median']:.3g}, max {v['max']:.3g} {unit}" if v else "-"


def markdown(result: dict, sizes: list[int]) -> str:
    """The tables of docs/explanation/multi_target.md: medians against N, trends, completeness."""
    out = []
    for scene, entry in result["scenes"].items():
        out += [f"**{scene}** ({entry['trials']} trials; a success of the mission -- every "
                f"target, the weighted lambda2 above 0 at every sub-step with the guard only "
                f"watching, no collision, every speed within its bound -- in "
                f"{entry['trials'] - len(entry['failed_trials'])})", "",
                "| metric (median) | " + " | ".join(f"N = {n}" for n in sizes)
                + " | Spearman rho (p) |",
                "| --- |" + " --- |" * (len(sizes) + 1)]  # fmt: skip
        for key, label in METRICS:
            per = entry[key]["percentiles"]
            cells = [f"{per[str(n)][2]:.3g}" if per.get(str(n)) else "-" for n in sizes]
            rho, p = entry[key]["spearman_rho"], entry[key]["spearman_p"]
            out.append(f"| {label.replace(chr(10), ' ')} | " + " | ".join(cells)
                       + f" | {rho:+.2f} ({p:.1g}) |")  # fmt: skip
        speed = entry.get("sim_over_wall_median", {})
        out.append("| simulated / wall time (one core per trial) | "
                   + " | ".join(f"{speed[str(n)]:.1f}x" if str(n) in speed else "-" for n in sizes)
                   + " | |")  # fmt: skip
        dyn = entry.get("dynamics")
        if dyn:
            out.append(
                f"\nDynamics: {dyn['controller_successes']} of {entry['trials']} trials a "
                f"success of the controller; trials with a sub-step outside the safe set "
                f"{dyn['trials_with_safe_set_exits']}, with a guard intervention "
                f"{dyn['trials_with_guard_interventions']}, with a step-rule miss "
                f"{dyn['trials_with_tolerance_misses']}, with an anchor outside its ball "
                f"{dyn['trials_with_anchor_outside_steps']}; top speed "
                f"{_mm(dyn, 'max_speed_mps', 'm/s')}; top acceleration "
                f"{_mm(dyn, 'max_accel_mps2', 'm/s^2')}; energy added by the integrator "
                f"{_mm(dyn, 'energy_added_j', 'J')}; reference of eq. (16) off the robot "
                "by "
                f"{_mm(dyn, 'reference_filter_max_deviation_m', 'm')}, its top acceleration "
                f"{_mm(dyn, 'reference_filter_max_accel_mps2', 'm/s^2')}; longest prime vacancy "
                f"{_mm(dyn, 'longest_prime_vacancy_steps', 'steps')}, above N - 1 in "
                f"{_over_bound(dyn['vacancy_above_bound'])}; "
                f"{dyn['substeps_per_step']:.1f} sub-steps per control step, "
                f"{100 * dyn['rejected_share']:.1f} % of candidates rejected.")  # fmt: skip
        for f in entry["failed_trials"]:
            out.append(f"\nFailed: N = {f['n_robots']}, seed {f['seed']}: {f['why']}.")
        if "targets_total" in entry:
            low = entry.get("min_lambda2_trial") or {}
            pending = entry["targets_total"] - entry["targets_reached"] - entry["targets_dropped"]
            out.append(f"\nTargets: {entry['targets_reached']:,} of {entry['targets_total']:,} "
                       f"reached, {entry['targets_dropped']} dropped, {pending} pending at the "
                       f"horizon; {entry['trials_helped']} trials asked for help; smallest "
                       f"weighted lambda2 {entry['min_lambda2_weighted']:.2g} (N = "
                       f"{low.get('n_robots')}, seed {low.get('seed')}); "
                       f"{entry['collisions']} collisions.")  # fmt: skip
        out.append("")
    scenes = result["scenes"].values()
    trials = sum(e["trials"] for e in scenes)
    total = sum(e["trial_wall_s_total"] for e in scenes)
    cpu = sum(e.get("trial_cpu_s_total", 0.0) for e in scenes)
    if trials and cpu:
        out.append(f"Processor time: {cpu:,.0f} s over {trials} trials ({cpu / trials:.1f} s "
                   f"per trial); 1,800 trials on 2 cores at that rate: "
                   f"{1800 * cpu / trials / 2 / 3600:.2f} h.")  # fmt: skip
    if trials:
        out.append(f"All scenes: {trials} trials, {total:,.0f} trial-seconds "
                   f"({total / trials:.0f} s per trial); 1,800 trials on 2 cores at that "
                   f"rate: {1800 * total / trials / 2 / 3600:.1f} h.")  # fmt: skip
    wall = result.get("wall_time_s", {})
    if wall and set(wall) == set(result["scenes"]):  # the run that made these trials
        parts = ", ".join(f"{scene} {s:,.0f} s" for scene, s in wall.items())
        out.append(f"Wall time of the run that made them: {sum(wall.values()):,.0f} s "
                   f"({sum(wall.values()) / 3600:.2f} h; {parts}).")  # fmt: skip
    return "\n".join(out)


def figure(result: dict, sizes: list[int], path: Path) -> None:
    plt = pyplot()
    fig, axes = plt.subplots(len(METRICS), len(SCENES), figsize=(11, 10), squeeze=False)
    for col, scene in enumerate(SCENES):
        entry = result["scenes"].get(scene)
        for row, (key, label) in enumerate(METRICS):
            ax = axes[row][col]
            if entry is None:
                ax.set_axis_off()
                continue
            per = entry[key]["percentiles"]
            xs = [s for s in sizes if per.get(str(s))]
            p = np.array([per[str(s)] for s in xs])
            if len(xs):
                ax.fill_between(xs, p[:, 0], p[:, 4], alpha=0.15, color="tab:blue",
                                label="10-90 %")  # fmt: skip
                ax.fill_between(xs, p[:, 1], p[:, 3], alpha=0.3, color="tab:blue",
                                label="25-75 %")  # fmt: skip
                ax.plot(xs, p[:, 2], "o-", color="tab:blue", label="median")
            ax.set_xticks(sizes)
            ax.grid(alpha=0.3)
            if col == 0:
                ax.set_ylabel(label)
            if row == 0:
                ax.set_title(f"{scene} ({entry['trials']} trials)")
            if row == len(METRICS) - 1:
                ax.set_xlabel("number of robots N")
    axes[0][0].legend(fontsize=7)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=100, help="target configurations per N")
    ap.add_argument("--first-seed", type=int, default=0,
                    help="run configurations FIRST .. FIRST+SEEDS-1 (to time a slice)")  # fmt: skip
    ap.add_argument("--sizes", type=int, nargs="+", default=[10, 15, 20, 25, 30, 35])
    ap.add_argument("--scenes", nargs="+", default=list(SCENES))
    ap.add_argument("--runs", type=Path, default=ROOT / "runs" / "fig9")
    ap.add_argument("--workers", type=int, default=os.cpu_count() or 1)
    ap.add_argument("--no-run", action="store_true", help="only summarise finished trials")
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results" / "fig9.json")
    ap.add_argument("--figure", type=Path,
                    default=ROOT / "docs" / "figures" / "multi_target_fig9.png")  # fmt: skip
    a = ap.parse_args()
    result: dict = {"machine": machine(), "seeds": a.seeds, "sizes": a.sizes, "scenes": {},
                    "wall_time_s": {}}  # fmt: skip
    if a.no_run and a.out.exists():  # keep the wall times of the run that made the trials
        result["wall_time_s"] = json.loads(a.out.read_text()).get("wall_time_s", {})
    for scene in a.scenes:
        out = a.runs / scene
        if not a.no_run:
            chosen = list(range(a.first_seed, a.first_seed + a.seeds))
            result["wall_time_s"][scene] = run_column(scene, out, chosen, a.sizes, a.workers)
        seeds = None if a.no_run else a.first_seed + a.seeds  # a summary: every finished seed
        result["scenes"][scene] = summarise(load_rows(out, a.sizes, seeds), a.sizes)
        s = result["scenes"][scene]
        print(f"{scene}: {s['trials']} trials, complete {s['complete_share']}, completion "
              f"median ratio N={a.sizes[-1]}/N={a.sizes[0]}: "
              f"{s.get('completion_median_ratio_last_first')}", flush=True)  # fmt: skip
    result["markdown"] = markdown(result, a.sizes)
    print(result["markdown"])
    a.out.write_text(json.dumps(result, indent=1) + "\n")
    figure(result, a.sizes, a.figure)
    print(f"wrote {a.out} and {a.figure}")


if __name__ == "__main__":
    main()
