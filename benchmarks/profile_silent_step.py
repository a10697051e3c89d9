"""Where the 20-robot ``silent`` step's CPU time goes, inside the benchmark's own loop.

Runs ``bench_silent.bench``'s loop (sensing with occlusion, the Local Steering Strategy,
team metrics; 20 robots, ``TETHER_JIT=on``) and charges each call of the parts below
to its name (CPU clock read around each call, ~1 us per reading included). Parts are
nested: ``sense`` contains the sensing kernels, ``step`` the leader's carrot and
``team_steps``, and so on. Timings inside the loop, not in a tight loop of one call:
the team contracts to ~17 neighbours per robot, and every call meets cold caches.

    TETHER_JIT=on python benchmarks/profile_silent_step.py [--steps 2000]
"""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from typing import Any

import numpy as np

import tether.graph.metrics_kernels as metrics_kernels
import tether.sensing.draws_kernels as draws_kernels
import tether.sensing.robots as robots
import tether.sensing.robots_kernels as robots_kernels
import tether.silent.steering_kernels as steering_kernels
import tether.silent.strategy as strategy_mod
import tether.sim as sim
from tether.paths.trajectory import Polyline
from tether.sensing import SensorModel
from tether.world.world import World

PARTS = [
    (robots, "sense"),
    (robots_kernels, "sense_pairs_kernel"),
    (draws_kernels, "sensor_errors_kernel"),
    (robots_kernels, "noise_kernel"),
    (robots_kernels, "sense_noisy_kernel"),
    (strategy_mod.SilentStrategy, "step"),
    (strategy_mod.SilentStrategy, "leader_target"),
    (steering_kernels, "team_steps_kernel"),
    (steering_kernels, "silent_step_kernel"),
    (sim, "team_metrics"),
    (metrics_kernels, "team_metrics_kernel"),
]


def _charged(fn: Callable, name: str, acc: dict[str, float]) -> Callable:
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        t0 = time.process_time()
        out = fn(*args, **kwargs)
        acc[name] = acc.get(name, 0.0) + time.process_time() - t0
        return out

    return wrapper


def profile(steps: int) -> dict[str, float]:
    """Microseconds per step of each part (and ``total``) over ``steps`` steps."""
    acc: dict[str, float] = {}
    for owner, name in PARTS:
        setattr(owner, name, _charged(getattr(owner, name), name, acc))
    rng = np.random.default_rng(0)
    side = np.stack(np.meshgrid(np.arange(5), np.arange(5), indexing="ij"), -1).reshape(-1, 2)
    pos = side[:20] * 7.0 + rng.uniform(-0.25, 0.25, (20, 2)) * 7.0  # bench_silent's team
    world = World(dim=2)
    sensor = SensorModel(15.0, body_radius_m=0.5, radial_error_m=0.45,
                         angular_error_rad=np.radians(12), noise="uniform")  # fmt: skip
    strategy = strategy_mod.SilentStrategy(
        d_max_m=15.0, trajectory=Polyline(np.array([pos[0], pos[0] + [1000.0, 0.0]])),
        leader=0, d0_m=8.0, radial_error_m=0.45, angular_error_rad=np.radians(12),
    )  # fmt: skip
    state = sim.TeamState.at_rest(pos)
    strategy.reset(world, state, rng)
    for warm in (True, False):
        acc.clear()
        t0 = time.process_time()
        for k in range(2 if warm else steps):
            obs = robots.sense(state.positions, sensor, rng, world)
            state = strategy.step(sim.StepContext(k, float(k), 1.0, world, state, obs, rng))
            sim.team_metrics(k, float(k), state.positions, obs, 1.0)
        total = time.process_time() - t0
    out = {name: 1e6 * acc.get(name, 0.0) / steps for _, name in PARTS}
    out["total"] = 1e6 * total / steps
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=2000)
    for name, us in profile(ap.parse_args().steps).items():
        print(f"{name:24s} {us:8.1f} us per step")


if __name__ == "__main__":
    main()
