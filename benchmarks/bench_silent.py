"""Steps per second of the non-communicating strategy for 20, 1,000 and 10,000 robots.

One step = sensing (k-d tree neighbour search, occlusion, noise) + the Local
Steering Strategy for every robot + team metrics (components; lambda2 only up
to 500 robots). Robot density is kept constant (about 6 neighbours in range),
so a neighbour search that is not all-pairs shows as near-linear scaling.

Usage: python benchmarks/bench_silent.py [--steps 20] [--out benchmarks/results/silent.json]
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from _machine import machine
from tether.paths.trajectory import Polyline
from tether.sensing import SensorModel, sense
from tether.silent.strategy import SilentStrategy
from tether.sim import StepContext, TeamState, team_metrics
from tether.world.world import World


def lattice_team(n: int, spacing_m: float, rng: np.random.Generator) -> np.ndarray:
    side = int(np.ceil(np.sqrt(n)))
    grid = np.stack(np.meshgrid(np.arange(side), np.arange(side), indexing="ij"), -1)
    pts = grid.reshape(-1, 2)[:n] * spacing_m
    return pts + rng.uniform(-0.25, 0.25, pts.shape) * spacing_m


def bench(n: int, steps: int) -> dict[str, float]:
    rng = np.random.default_rng(0)
    world = World(dim=2)
    pos = lattice_team(n, 7.0, rng)
    sensor = SensorModel(
        15.0,
        body_radius_m=0.5,
        radial_error_m=0.45,
        angular_error_rad=np.radians(12),
        noise="uniform",
    )
    strategy = SilentStrategy(
        d_max_m=15.0,
        trajectory=Polyline(np.array([pos[0], pos[0] + [1000.0, 0.0]])),
        leader=0,
        d0_m=8.0,
        radial_error_m=0.45,
        angular_error_rad=np.radians(12),
    )
    state = TeamState.at_rest(pos)
    strategy.reset(world, state, rng)
    t_sense = t_act = t_metrics = 0.0
    links = 0
    for k in range(steps):
        t0 = time.perf_counter()
        obs = sense(state.positions, sensor, rng, world)
        t1 = time.perf_counter()
        state = strategy.step(StepContext(k, float(k), 1.0, world, state, obs, rng))
        t2 = time.perf_counter()
        rec = team_metrics(k, float(k), state.positions, obs, 1.0)
        t3 = time.perf_counter()
        t_sense += t1 - t0
        t_act += t2 - t1
        t_metrics += t3 - t2
        links += rec.n_links
    total = t_sense + t_act + t_metrics
    return {
        "n_robots": n,
        "steps": steps,
        "steps_per_s": steps / total,
        "ms_per_step": 1e3 * total / steps,
        "ms_sense": 1e3 * t_sense / steps,
        "ms_strategy": 1e3 * t_act / steps,
        "ms_metrics": 1e3 * t_metrics / steps,
        "mean_links": links / steps,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=20)
    parser.add_argument("--out", type=Path, default=Path(__file__).parent / "results/silent.json")
    args = parser.parse_args()
    rows = []
    for n in (20, 1_000, 10_000):
        steps = args.steps * (10 if n == 20 else 1)
        row = bench(n, steps)
        rows.append(row)
        print(
            f"n={n:>6}: {row['steps_per_s']:9.1f} steps/s  ({row['ms_per_step']:.2f} ms: "
            f"sense {row['ms_sense']:.2f}, strategy {row['ms_strategy']:.2f}, "
            f"metrics {row['ms_metrics']:.2f}; {row['mean_links']:.0f} links)"
        )
    ratio = rows[2]["ms_per_step"] / rows[1]["ms_per_step"]
    print(f"10,000 / 1,000 robots time ratio: {ratio:.1f} (all-pairs would be ~100)")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(
        json.dumps({"machine": machine(), "results": rows, "ratio_10k_over_1k": ratio}, indent=2)
        + "\n"
    )
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
