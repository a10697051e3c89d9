"""Wall time of a ``multi_target`` trial against simulated time, old code against new.

The Fig. 9 campaign of the continuous paper is 1,800 trials of up to 35 robots; it fits
in about two hours on two cores only if a 35-robot town trial runs at 100x real time or
more (issue 14). Measured here, each in a fresh process:

* ``trial``: a ``multi_target`` scenario (a built-in name or a YAML file such as a
  Fig. 9 run folder's ``scenario.yaml``; default the town, 35 robots) for ``--steps``
  control steps (0: the scenario's ``sim.max_steps``, i.e. the whole trial until the
  targets are done), recorded as ``tether run`` records it (the run's
  :class:`~tether.record.TrajectoryRecorder`, ``output.record_every``): process
  start-up (imports), the compiled kernels' loading (``kernel_load_s``: numba's
  start-up and its cache; 0 for code without kernels), ``build`` (world, team,
  strategy), the first control step, then per control step everything the loop does
  (strategy step + sensing + team metrics + recording), wall and CPU time: the median
  step, the mean over the trial, and simulated time over wall / CPU time
  (``real_time_factor``, ``real_time_factor_cpu``; the goal of issue 10 is 100x on one
  core, i.e. a mean step of at most 1 ms CPU at ``dt = 0.1 s``);
* ``cli``: whole ``tether run`` commands (start-up included): ``silent_demo`` (no
  kernels: must not get slower), and short continuous runs;
* ``compile`` (``--cold``): the first step with an empty numba cache (compilation).

With ``--compare-src DIR`` (e.g. ``git worktree add /tmp/old <commit>``, then
``/tmp/old/src``) every measurement is repeated with that code, the two interleaved
(new, old, new, old, ...) so that both see the same load; medians are reported, and the
load average before and after. Both codes compute the same trajectories (bit for bit),
so they do the same work.

Usage::

    python benchmarks/bench_multi_target.py --compare-src /tmp/old/src [--repeats 3]
        [--steps 600] [--robots 35] [--scenario multi_target_town] [--cold]
        [--out benchmarks/results/multi_target.json]

Writes ``benchmarks/results/multi_target.json``.
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

OUT = Path(__file__).parent / "results" / "multi_target.json"
CLI_RUNS = {
    "silent_demo": ["silent_demo"],
    "connectivity_empty_100_steps": ["connectivity_empty", "--set", "sim.max_steps=100"],
    "multi_target_town_50_steps": ["multi_target_town", "--set", "sim.max_steps=50"],
}


def worker_trial(scenario: str, robots: int, steps: int, jit_mode: str) -> dict:
    """One trial in this process (the ``tether`` on ``sys.path``); timings as a dict."""
    t0 = time.perf_counter()
    import numpy as np

    from tether.config import load_scenario
    from tether.record import TrajectoryRecorder
    from tether.runner import build
    from tether.sim import simulate

    out: dict = {"import_s": time.perf_counter() - t0, "kernel_load_s": 0.0}
    try:
        from tether import jit
    except ImportError:
        jit = None
    out["has_kernels"] = jit is not None
    if jit is not None and jit_mode != "auto":
        jit.set_enabled(jit_mode == "on")
    if jit is not None and jit.enabled():
        t = time.perf_counter()
        from tether.continuous.kernels import warm_up

        warm_up()
        out["kernel_load_s"] = time.perf_counter() - t
    sc = load_scenario(scenario)
    if robots:
        sc.team.n_robots = robots
    steps = steps or sc.sim.max_steps
    t = time.perf_counter()
    built = build(sc, sc.seed)
    out["build_s"] = time.perf_counter() - t

    stamps: list[float] = []
    cpu_stamps: list[float] = []

    class Stamps(TrajectoryRecorder):
        """The run's recorder; the clocks read once per recorded step (after recording)."""

        def record(self, *args: object) -> None:
            super().record(*args)
            stamps.append(time.perf_counter())
            cpu_stamps.append(time.process_time())

    recorder = Stamps(every=sc.output.record_every)
    t, c = time.perf_counter(), time.process_time()
    res = simulate(built.world, built.sensor, built.strategy, built.initial,
                   dt_s=sc.sim.dt_s, max_steps=steps, rng=built.rng,
                   collision_distance_m=sc.sim.collision_distance_m, recorder=recorder)  # fmt: skip
    wall, cpu = time.perf_counter() - t, time.process_time() - c
    per_step = np.diff(stamps)
    per_step_cpu = np.diff(cpu_stamps)
    out.update(
        scenario_name=sc.name,
        robots=len(built.initial.positions),
        steps=res.steps,
        sim_time_s=res.sim_time_s,
        wall_s=wall,
        cpu_s=cpu,
        reset_s=stamps[0] - t,
        first_step_s=float(per_step[0]),
        step_median_s=float(np.median(per_step[1:])),
        step_p90_s=float(np.quantile(per_step[1:], 0.9)),
        # CPU time of the process per step (less sensitive to other jobs than wall time)
        step_median_cpu_s=float(np.median(per_step_cpu[1:])),
        # every step after the first, the start-up's plans (reset) and step 1 excluded
        step_mean_cpu_s=float(np.mean(per_step_cpu[1:])),
        real_time_factor=res.sim_time_s / wall,
        real_time_factor_cpu=res.sim_time_s / cpu,
        real_time_factor_steady=sc.sim.dt_s / float(np.median(per_step[1:])),
        real_time_factor_steady_cpu=sc.sim.dt_s / float(np.mean(per_step_cpu[1:])),
        substeps=res.strategy_metrics.get("substeps"),
        final_positions_sum=float(np.sum(res.final_state.positions)),
    )
    return out


def run_worker(src: Path | None, args: list[str], env: dict | None = None) -> dict:
    """This script as a worker with the ``tether`` of ``src`` (None: the current one)."""
    env = dict(os.environ, **(env or {}))
    if src is not None:
        env["PYTHONPATH"] = str(src)
    proc = subprocess.run([sys.executable, __file__, *args], env=env, check=True,
                          capture_output=True, text=True)  # fmt: skip
    return json.loads(proc.stdout.strip().splitlines()[-1])


def time_cli(src: Path | None, argv: list[str]) -> float:
    """Wall time of ``tether run ARGV --no-figures`` in a fresh process."""
    env = dict(os.environ)
    if src is not None:
        env["PYTHONPATH"] = str(src)
    code = "import sys; from tether.cli import main; sys.argv = ['tether', *sys.argv[1:]]; main()"
    with tempfile.TemporaryDirectory() as tmp:
        t = time.perf_counter()
        cmd = [sys.executable, "-c", code, "run", *argv, "--no-figures", "--out", f"{tmp}/run"]
        subprocess.run(cmd, env=env, check=True, capture_output=True)
        return time.perf_counter() - t


def medians(rows: list[dict]) -> dict:
    keys = [k for k, v in rows[0].items() if type(v) in (int, float)]
    return {k: statistics.median(r[k] for r in rows) for k in keys}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--compare-src", type=Path, help="src directory of the code to compare with")
    ap.add_argument("--scenario", default="multi_target_town")
    ap.add_argument("--robots", type=int, default=35, help="0: the scenario's team size")
    ap.add_argument("--steps", type=int, default=600, help="0: the scenario's sim.max_steps")
    ap.add_argument("--out", type=Path, default=OUT, help="the JSON written")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--cli-repeats", type=int, default=5)
    ap.add_argument("--cold", action="store_true", help="also time compilation (empty cache)")
    ap.add_argument("--skip-cli", action="store_true")
    ap.add_argument("--conditions", default="", help="free text: load on the machine etc.")
    ap.add_argument("--worker", choices=["trial"], help=argparse.SUPPRESS)
    ap.add_argument("--jit", default="on", choices=["on", "off", "auto"], help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker == "trial":
        print(json.dumps(worker_trial(args.scenario, args.robots, args.steps, args.jit)))
        return

    load_before = os.getloadavg()
    trial_args = ["--worker", "trial", "--scenario", args.scenario, "--robots", str(args.robots),
                  "--steps", str(args.steps)]  # fmt: skip
    codes = {"new": None}
    if args.compare_src is not None:
        codes["old"] = args.compare_src
    rows: dict[str, list[dict]] = {k: [] for k in codes}
    for rep in range(args.repeats):
        for label, src in codes.items():
            row = run_worker(src, trial_args)
            row["load_1min"] = os.getloadavg()[0]
            rows[label].append(row)
            print(f"trial {rep} {label}: {row['steps']} steps, {row['real_time_factor']:.1f}x "
                  f"real time ({row['real_time_factor_cpu']:.1f}x on CPU time), step median "
                  f"{row['step_median_s'] * 1e3:.2f} ms (CPU "
                  f"{row['step_median_cpu_s'] * 1e3:.2f} ms, mean "
                  f"{row['step_mean_cpu_s'] * 1e3:.2f} ms), kernels "
                  f"{row['kernel_load_s']:.2f} s, build {row['build_s']:.2f} s, "
                  f"load {row['load_1min']:.1f}",
                  flush=True)  # fmt: skip
    out: dict = {
        "benchmark": "multi_target trial: wall time vs simulated time (issue 14)",
        "command": " ".join(["python", *sys.argv]),
        "conditions": args.conditions,
        "date": dt.datetime.now(dt.timezone.utc).isoformat(),
        "scenario": args.scenario,
        "robots": args.robots,
        "steps": args.steps,
        "trial": {k: {"median": medians(v), "runs": v} for k, v in rows.items()},
    }
    if "old" in rows:
        same = {r["final_positions_sum"] for r in rows["new"] + rows["old"]}
        out["same_trajectory"] = len(same) == 1
        new, old = out["trial"]["new"]["median"], out["trial"]["old"]["median"]
        out["speedup_old_over_new"] = {
            "step_median": old["step_median_s"] / new["step_median_s"],
            "step_median_cpu": old["step_median_cpu_s"] / new["step_median_cpu_s"],
            "step_mean_cpu": old["step_mean_cpu_s"] / new["step_mean_cpu_s"],
            "trial_cpu": old["cpu_s"] / new["cpu_s"],
            "trial_wall": old["wall_s"] / new["wall_s"],
        }
    if args.cold:
        with tempfile.TemporaryDirectory() as cache:
            cold = run_worker(None, trial_args, env={"NUMBA_CACHE_DIR": cache})
        out["compile"] = {"kernel_load_cold_s": cold["kernel_load_s"], "run": cold}
        print(f"cold cache: kernels compiled in {cold['kernel_load_s']:.1f} s", flush=True)
    if not args.skip_cli:
        cli: dict[str, dict[str, list[float]]] = {}
        for name, argv in CLI_RUNS.items():
            cli[name] = {k: [] for k in codes}
            for _ in range(args.cli_repeats):
                for label, src in codes.items():
                    cli[name][label].append(time_cli(src, argv))
            took = ", ".join(f"{k} {statistics.median(v):.2f} s" for k, v in cli[name].items())
            print(f"tether run {name}: {took}", flush=True)
        out["cli_wall_s"] = {n: {k: {"median": statistics.median(v), "runs": v}
                                 for k, v in d.items()} for n, d in cli.items()}  # fmt: skip
    from tether.runfolder import machine

    out["machine"] = machine()
    out["load_average_before_after"] = [load_before, os.getloadavg()]
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(out, indent=2) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
