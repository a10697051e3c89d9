"""Team placement ``random_connected``: 1,000, 10,000 and 100,000 robots, new vs old.

The silent demo's setting (free 2-D space, ``spacing_m = 8``, ``min_separation_m
= 2``). The new placement (tether.team.random_connected, O(n log n): batched
candidates against a k-d tree, full anchors retired) is timed at every size; the
old one-robot-at-a-time placement (tests/_placement_reference.py, every
candidate against every robot) only up to ``--old-up-to`` robots, since it grows
as about n^2.5 (results/placement.json, on a 2-core machine shared with other
work: old 4 s for 1,000 robots and 19 min for 10,000; new 0.3 s, 1.2 s and 20 s
for 1,000, 10,000 and 100,000). Each placement is checked: connected disc graph
of radius ``spacing_m``, robots at least ``min_separation_m`` apart.

Usage: python benchmarks/bench_placement.py [--sizes 1000 10000 100000] [--old-up-to 3000]
       [--out benchmarks/results/placement.json]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from _placement_reference import random_connected as old_random_connected
from tether.graph import is_connected, pairs_within
from tether.runfolder import machine
from tether.team import random_connected
from tether.world.world import World

SPACING_M, MIN_SEPARATION_M = 8.0, 2.0


def timed(place, n: int, seed: int) -> dict[str, float]:
    start = time.perf_counter()
    pos = place(n, World(dim=2), np.random.default_rng(seed), SPACING_M, MIN_SEPARATION_M)
    seconds = time.perf_counter() - start
    nearest, _ = cKDTree(pos).query(pos, k=2)
    assert len(pos) == n and nearest[:, 1].min() >= MIN_SEPARATION_M
    assert is_connected(n, pairs_within(pos, SPACING_M))
    centre = pos.mean(axis=0)
    return {
        "n_robots": n,
        "seconds": seconds,
        "radius_of_gyration_m": float(np.sqrt(((pos - centre) ** 2).sum(axis=1).mean())),
        "mean_nearest_m": float(nearest[:, 1].mean()),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1_000, 10_000, 100_000])
    parser.add_argument("--old-up-to", type=int, default=3_000)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument(
        "--out", type=Path, default=Path(__file__).parent / "results/placement.json"
    )
    args = parser.parse_args()
    rows = []
    for n in args.sizes:
        row = {"n_robots": n, "new": timed(random_connected, n, args.seed)}
        if n <= args.old_up_to:
            row["old"] = timed(old_random_connected, n, args.seed)
        rows.append(row)
        old = row.get("old")
        print(
            f"n={n:>7,}: new {row['new']['seconds']:8.2f} s"
            + (f", old {old['seconds']:8.2f} s" if old else ", old not run (too slow)")
        )
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(
        json.dumps(
            {
                "machine": machine(),
                "setting": {"spacing_m": SPACING_M, "min_separation_m": MIN_SEPARATION_M},
                "results": rows,
            },
            indent=2,
        )
        + "\n"
    )
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
