"""Re-run the Fig. 9 trials in which a prime asked for help, with other settings.

A setting of the helpers (``help_*`` of ``multi_target``,
:mod:`tether.continuous.exploration.recruit`) changes only the trials in which a prime
traveler asked for help: in every other trial nobody is recruited, so it is bit for bit
the same (the request draws no random number). Its effect on a whole campaign is
therefore measured by re-running those trials alone.

Reads ``RUNS/<scene>/sweep.parquet`` of a finished campaign (``benchmarks/fig9.py``),
picks the trials with ``help_requests > 0`` (configuration seeds below ``--seeds``;
with ``--only-failed`` those that failed the completeness check),
re-runs each trial's ``scenario.yaml`` with the ``--set`` overrides (one process per
trial, ``--workers`` at once) into ``OUT``, and prints per scene: the trials that pass
the completeness check before and after (every target, lambda2 > 0, no collision, as
``fig9.py`` checks), the targets reached and dropped, the paired completion times
(median and the trials faster / slower) and the helper robot-seconds; then every
trial's before -> after. Writes the table as JSON (``--json``).

Usage::

    python benchmarks/rerun_helped.py RUNS --out OUT --set strategy.params.help_lambda_factor=0.1
        [--seeds 18] [--scenes town office empty] [--workers 2] [--only-failed] [--json PATH]
"""

from __future__ import annotations

import argparse
import json
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq

from fig9 import failure
from tether.quicksize import load_scenario_at
from tether.runfolder import machine
from tether.runner import run

KEYS = ("targets_total", "targets_reached", "targets_dropped", "completion_time_s",
        "min_lambda2_weighted", "collisions", "help_requests", "helper_robot_s",
        "mean_explorer_distance_m", "max_explorer_stretch_m", "mean_lambda2_weighted")  # fmt: skip


def rerun(run_dir: str, out_dir: str, overrides: list[str]) -> dict:
    """One trial again with the overrides (as ``tether run ... --set`` applies them); its
    summary's keys of interest."""
    scenario = load_scenario_at(Path(run_dir) / "scenario.yaml", overrides=overrides)
    summary = run(scenario, out_dir=out_dir, figures=False).summary
    return {k: summary.get(k) for k in KEYS}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs", type=Path, help="a finished campaign of benchmarks/fig9.py")
    ap.add_argument("--out", type=Path, required=True, help="where the re-runs are written")
    ap.add_argument("--set", dest="overrides", action="append", default=[], required=True)
    ap.add_argument("--seeds", type=int, default=100, help="configuration seeds below this")
    ap.add_argument("--scenes", nargs="+", default=["town", "office", "empty"])
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--only-failed", action="store_true",
                    help="only the helped trials that failed the completeness check")  # fmt: skip
    ap.add_argument("--json", type=Path, help="write the comparison here")
    a = ap.parse_args()
    jobs = []
    for scene in a.scenes:
        for row in pq.read_table(a.runs / scene / "sweep.parquet").to_pylist():
            if (
                (row["help_requests"] or 0) > 0
                and row["seed"] < a.seeds
                and (not a.only_failed or failure(row))
            ):
                rel = Path(row["run_dir"]).relative_to(a.runs)
                jobs.append((scene, row, str(a.out / rel)))
    print(f"{len(jobs)} trials asked for help; re-running with {a.overrides}", flush=True)
    with ProcessPoolExecutor(a.workers) as pool:
        futures = [pool.submit(rerun, row["run_dir"], out, a.overrides) for _, row, out in jobs]
        after = [f.result() for f in futures]
    result: dict = {"machine": machine(), "overrides": a.overrides, "seeds": a.seeds,
                    "scenes": {}}  # fmt: skip
    for scene in a.scenes:
        pairs = [(row, new) for (s, row, _), new in zip(jobs, after, strict=True) if s == scene]
        if not pairs:
            continue
        t_old = np.array([r["completion_time_s"] for r, _ in pairs], dtype=float)
        t_new = np.array([n["completion_time_s"] for _, n in pairs], dtype=float)
        entry = {
            "trials": len(pairs),
            "complete_before": sum(not failure(r) for r, _ in pairs),
            "complete_after": sum(not failure({**r, **n}) for r, n in pairs),
            "reached_before": sum(r["targets_reached"] for r, _ in pairs),
            "reached_after": sum(n["targets_reached"] for _, n in pairs),
            "targets": sum(r["targets_total"] for r, _ in pairs),
            "dropped_before": sum(r["targets_dropped"] for r, _ in pairs),
            "dropped_after": sum(n["targets_dropped"] for _, n in pairs),
            "completion_median_before_s": float(np.median(t_old)),
            "completion_median_after_s": float(np.median(t_new)),
            "faster": int((t_new < t_old).sum()), "slower": int((t_new > t_old).sum()),
            "helper_robot_s_before": float(sum(r["helper_robot_s"] for r, _ in pairs)),
            "helper_robot_s_after": float(sum(n["helper_robot_s"] for _, n in pairs)),
            "min_lambda2_weighted_after": min(n["min_lambda2_weighted"] for _, n in pairs),
            "collisions_after": int(sum(n["collisions"] for _, n in pairs)),
            "trials_detail": [
                {"n_robots": r["param:team.n_robots"], "seed": r["seed"],
                 "before": {k: r[k] for k in KEYS}, "after": n} for r, n in pairs
            ],
        }  # fmt: skip
        result["scenes"][scene] = entry
        print(f"{scene}: {entry['trials']} trials; complete {entry['complete_before']} -> "
              f"{entry['complete_after']}; targets reached {entry['reached_before']} -> "
              f"{entry['reached_after']} of {entry['targets']} (dropped "
              f"{entry['dropped_before']} -> {entry['dropped_after']}); completion median "
              f"{entry['completion_median_before_s']:.1f} -> "
              f"{entry['completion_median_after_s']:.1f} s ({entry['faster']} faster, "
              f"{entry['slower']} slower); helper robot-s "
              f"{entry['helper_robot_s_before']:.0f} -> {entry['helper_robot_s_after']:.0f}; "
              f"min weighted lambda2 {entry['min_lambda2_weighted_after']:.3g}, collisions "
              f"{entry['collisions_after']}")  # fmt: skip
        for d in entry["trials_detail"]:
            b, n = d["before"], d["after"]
            print(
                f"  N = {d['n_robots']}, seed {d['seed']}: {b['targets_reached']}/"
                f"{b['targets_total']} in {b['completion_time_s']} s -> "
                f"{n['targets_reached']}/{n['targets_total']} in {n['completion_time_s']} s"
            )
    if a.json:
        a.json.write_text(json.dumps(result, indent=1) + "\n")
        print(f"wrote {a.json}")


if __name__ == "__main__":
    main()
