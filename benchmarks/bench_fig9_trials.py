"""Fig. 9 trials of two source trees timed side by side: processor time and outcome per trial.

Runs the same trials (scene x team size x configuration, as in
``scenarios/paper/continuous_fig9_<scene>.yaml``) under this tree and under
``--peer-root`` (another checkout, e.g. the commit before a change of the dynamics), in
two processes at once, one per core, each with its own ``PYTHONPATH``: both meet the same
load from the rest of the machine, and each trial is timed by its process's CPU clock
(``time.process_time``) around the simulation alone (no start-up, no compile: every
kernel is loaded by a warm-up trial first). Writes ``benchmarks/results/fig9_trials.json``:
per tree and trial the processor time, simulated time, sub-steps and the controller's
metrics, and per tree the totals and the ratio of simulated to processor time.

    python benchmarks/bench_fig9_trials.py --peer-root ../old            # 3 scenes x 6 N x 3
    python benchmarks/bench_fig9_trials.py --peer-root ../old --seeds 0 1 --sizes 35
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
KEYS = ("completion_time_s", "targets_reached", "targets_total", "substeps",
        "rejected_substeps", "stalls", "min_lambda2_weighted", "controller_success",
        "safe_set_exits", "guard_interventions", "max_speed_mps", "max_accel_mps2")  # fmt: skip


def worker(root: Path, scenes: list[str], sizes: list[int], seeds: list[int]) -> None:
    """Run the trials with the tether found on ``sys.path``; one JSON line per trial."""
    import numpy as np

    from tether.config import load_scenario
    from tether.runner import build
    from tether.sim import simulate

    def trial(scene: str, n: int, seed: int, steps: int | None = None) -> dict:
        sc = load_scenario(root / "src" / "tether" / "scenarios" / "paper"
                           / f"continuous_fig9_{scene}.yaml")  # fmt: skip
        sc.team.n_robots = n
        # the configuration is the run seed, as `tether sweep` runs it (set here too: the
        # other checkout's build may draw the targets from the scenario's own seed)
        sc.seed = seed
        b = build(sc, seed)
        cpu = time.process_time()
        res = simulate(b.world, b.sensor, b.strategy, b.initial, dt_s=sc.sim.dt_s,
                       max_steps=steps or sc.sim.max_steps, rng=b.rng,
                       collision_distance_m=sc.sim.collision_distance_m)  # fmt: skip
        cpu = time.process_time() - cpu
        m = res.strategy_metrics
        return {
            "scene": scene,
            "n": n,
            "seed": seed,
            "cpu_s": cpu,
            "sim_s": res.sim_time_s,
            "collisions": int(sum(r.collisions for r in res.records)),
            **{
                k: (
                    None if k not in m else (float(m[k]) if isinstance(m[k], np.floating) else m[k])
                )
                for k in KEYS
            },
        }

    for scene in scenes:  # warm-up: compile or load every kernel the trials use
        trial(scene, sizes[0], seeds[0], steps=20)
    for scene in scenes:
        for n in sizes:
            for seed in seeds:
                print(json.dumps(trial(scene, n, seed)), flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--peer-root", type=Path, required=True)
    ap.add_argument("--scenes", nargs="+", default=["empty", "town", "office"])
    ap.add_argument("--sizes", nargs="+", type=int, default=[10, 15, 20, 25, 30, 35])
    ap.add_argument("--seeds", nargs="+", type=int, default=[0, 1, 2])
    ap.add_argument("--worker", type=Path, help=argparse.SUPPRESS)
    ap.add_argument(
        "--out", type=Path, default=ROOT / "benchmarks" / "results" / "fig9_trials.json"
    )
    a = ap.parse_args()
    if a.worker is not None:
        worker(a.worker, a.scenes, a.sizes, a.seeds)
        return
    args = ["--scenes", *a.scenes, "--sizes", *map(str, a.sizes), "--seeds", *map(str, a.seeds)]
    procs = {}
    for name, root in (("new", ROOT), ("old", a.peer_root.resolve())):
        env = {**os.environ, "PYTHONPATH": str(root / "src"), "TETHER_JIT": "1",
               "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}  # fmt: skip
        procs[name] = subprocess.Popen([sys.executable, __file__, "--peer-root", str(root),
                                        "--worker", str(root), *args], env=env,
                                       stdout=subprocess.PIPE, text=True)  # fmt: skip
    rows = {name: [json.loads(line) for line in p.stdout] for name, p in procs.items()}
    for p in procs.values():
        p.wait()
    result: dict = {"trees": {}, "load_average": os.getloadavg()}
    for name, trials in rows.items():
        cpu = sum(t["cpu_s"] for t in trials)
        sim = sum(t["sim_s"] for t in trials)
        result["trees"][name] = {"trials": trials, "cpu_s_total": cpu, "sim_over_cpu": sim / cpu}
        print(f"{name}: {len(trials)} trials, {cpu:,.0f} s of processor time, simulated / "
              f"processor time {sim / cpu:.0f}x")  # fmt: skip
    new, old = (result["trees"][k]["cpu_s_total"] for k in ("new", "old"))
    result["cpu_ratio_new_over_old"] = new / old
    print(f"processor time new / old: {new / old:.2f}")
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.out.write_text(json.dumps(result, indent=1) + "\n")
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
