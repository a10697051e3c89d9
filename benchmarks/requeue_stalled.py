"""What if a ``multi_target`` target dropped as ``stalled`` were tried again later?

Re-runs a run folder's ``scenario.yaml`` and, when the watchdog drops a target as
``stalled``, gives it back to the same robot once (``strategy.add_target``, at the end of
its queue, so it is tried after its other targets). Prints the events of the re-queued
target and the robot's distance to it every ``--every-s`` seconds, then the summary's
target counts. An experiment, not a setting: it shows whether a later try, with the team
in another configuration, gets there (``docs/explanation/multi_target.md``).

Usage::

    python benchmarks/requeue_stalled.py RUN_FOLDER [--every-s 25]
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from tether.config import load_scenario
from tether.runner import build
from tether.sim import StepContext


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", type=Path, help="a run folder of a multi_target scenario")
    ap.add_argument("--every-s", type=float, default=25.0)
    args = ap.parse_args()
    scenario = load_scenario(args.run / "scenario.yaml")
    built = build(scenario)
    world, sensor, strategy, rng = built.world, built.sensor, built.strategy, built.rng
    dt, max_steps = float(scenario.sim.dt_s), int(scenario.sim.max_steps)
    every = max(1, round(args.every_s / dt))
    state = built.initial.copy()
    strategy.reset(world, state, rng)
    obs = strategy.sense(state, world, sensor, rng)
    requeued: dict[int, np.ndarray] = {}  # robot -> the target given back to it
    step = 0
    while step < max_steps and not strategy.done():
        held = {i: z for i, z in enumerate(strategy.planner.target) if z is not None}
        state = strategy.step(StepContext(step, step * dt, dt, world, state, obs, rng))
        step += 1
        for e in strategy.drain_events():
            if e["kind"] == "target_dropped" and e.get("reason") == "stalled":
                robot = int(e["robot"])
                if robot not in requeued:
                    where = held[robot].position_m.copy()
                    requeued[robot] = where
                    strategy.add_target(robot, where, stay_s=held[robot].stay_s)
                    print(f"{e['t_s']:.1f} s: robot {robot}'s target dropped as stalled; "
                          f"given back at {np.round(where, 2).tolist()}")  # fmt: skip
            elif requeued and int(e.get("robot", -1)) in requeued and e["kind"] != "role":
                print(f"{e['t_s']:.1f} s: {e['kind']} robot {e['robot']}")
        obs = strategy.sense(state, world, sensor, rng)
        if requeued and step % every == 0:
            d = {r: round(float(np.linalg.norm(state.positions[r] - z)), 2)
                 for r, z in requeued.items()}  # fmt: skip
            print(f"{step * dt:.1f} s: distance to the re-queued target {d}")
    m = strategy.metrics()
    print(f"end {step * dt:.1f} s: {m['targets_reached']} of {m['targets_total']} reached, "
          f"{m['targets_dropped']} dropped, completion {m['completion_time_s']}")  # fmt: skip


if __name__ == "__main__":
    main()
