"""CPU time of ``runner.build`` for a campaign's trials: the first in a process, then reused.

A Fig. 9 worker runs many trials on one fixed-layout world (``world.params.seed``); the
world, its distance field and its obstacle index are built by the first trial and
reused by the next ones (``runner.build_world``, ``ObstacleIndex.shared``). Prints and
saves the CPU seconds of the first build and the median of the next ones, per scene.

Usage: python benchmarks/bench_build.py [--trials 5] [--out benchmarks/results/build.json]
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from pathlib import Path

from tether.config import load_scenario
from tether.runfolder import machine
from tether.runner import build

ROOT = Path(__file__).resolve().parents[1]
SCENES = ("town", "office", "empty")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=5)
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results" / "build.json")
    args = ap.parse_args()
    result: dict = {"machine": machine(), "scenes": {}}
    for scene in SCENES:
        path = ROOT / "src" / "tether" / "scenarios" / "paper" / f"continuous_fig9_{scene}.yaml"
        sc = load_scenario(path)
        sc.sweep = {}
        cpu = []
        for seed in range(args.trials + 1):
            t = time.process_time()
            build(sc, seed)
            cpu.append(time.process_time() - t)
        result["scenes"][scene] = {"first_s": cpu[0], "next_median_s": statistics.median(cpu[1:])}
        print(f"{scene:7s} first build {cpu[0]:.2f} s CPU, next {statistics.median(cpu[1:]):.3f} s")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=2) + "\n")


if __name__ == "__main__":
    main()
