"""Speed of the exploration simulator (recurrent-connectivity paper setting).

12 robots, 900 steps on the 800 x 600 shared maps (``../shared/maps``; a
procedural office floor of the same size when they are absent), with the BS
planner (APX, delta = 4, theta in {1, 12}) and the Utility baseline. Prints
and writes ``benchmarks/results/exploration.json``: wall time, steps per
second, time split (move, sense, comm, strategy, metrics), plans and planning
times, final explored fraction.

    python benchmarks/bench_exploration.py [--steps 900] [--maps offices grass open]
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from tether.recurrent.baseline_utility import UtilityStrategy
from tether.recurrent.exploration.run import run_exploration
from tether.recurrent.exploration.sim import ExplorationConfig, random_base
from tether.recurrent.replanning import RecurrentStrategy
from tether.runfolder import machine

ROOT = Path(__file__).resolve().parents[1]
MAPS = ROOT / ".." / "shared" / "maps"
OUT = ROOT / "benchmarks" / "results" / "exploration.json"


def load(name: str) -> tuple[np.ndarray, str]:
    path = MAPS / f"{name}.png"
    if path.exists():
        from tether.world.maps import load_map

        return load_map(path, occupied_thresh=0.999, free_thresh=0.998).occupied, str(path)
    import tether.world.scenes  # noqa: F401
    from tether.registry import SCENES

    world = SCENES.get("office")(np.random.default_rng(0), dim=2, size_m=[80.0, 60.0])
    return world.grid.occupied, "procedural office 80 x 60 m (shared maps absent)"


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=900)
    ap.add_argument("--robots", type=int, default=12)
    ap.add_argument("--maps", nargs="+", default=["offices", "grass", "open"])
    ap.add_argument("--out", default=str(OUT))
    a = ap.parse_args(argv)
    rows = []
    for name in a.maps:
        occ, source = load(name)
        for label, make in (
            ("apx_theta1", lambda: RecurrentStrategy(theta=1)),
            ("apx_theta12", lambda: RecurrentStrategy(theta=12)),
            ("utility", lambda: UtilityStrategy(ratio=0.5)),
        ):
            cfg = ExplorationConfig(n_robots=a.robots, steps=a.steps)
            base = random_base(occ, cfg.coarse_factor, np.random.default_rng(0))
            res = run_exploration(occ, make(), cfg, base=base)
            row = {
                "map": name,
                "map_source": source,
                "map_cells": list(occ.shape),
                "strategy": label,
                "steps": a.steps,
                "n_robots": a.robots,
                "wall_time_s": round(res.wall_time_s, 3),
                "steps_per_s": round(a.steps / res.wall_time_s, 1),
                "time_split_s": {k: round(v, 3) for k, v in res.timing_s.items()},
                "plans": res.metrics.get("plans"),
                "planning_time_mean_s": round(res.metrics.get("planning_time_mean_s", 0.0), 4),
                "planning_time_max_s": round(res.metrics.get("planning_time_max_s", 0.0), 4),
                "final_explored_fraction": round(float(res.explored[-1]), 4),
            }
            rows.append(row)
            print(
                f"{name:8s} {label:12s} {row['wall_time_s']:7.2f} s  "
                f"{row['steps_per_s']:6.1f} steps/s  explored {row['final_explored_fraction']:.3f}"
                f"  plans {row['plans']}  split {row['time_split_s']}",
                flush=True,
            )
    out = {
        "benchmark": "exploration simulator (recurrent connectivity, Banfi et al. 2016)",
        "machine": machine(),
        "results": rows,
    }
    Path(a.out).parent.mkdir(parents=True, exist_ok=True)
    Path(a.out).write_text(json.dumps(out, indent=2) + "\n")
    return out


if __name__ == "__main__":
    main(sys.argv[1:])
