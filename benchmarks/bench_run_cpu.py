"""CPU time of a whole ``tether run <scenario> --no-figures`` process, two trees interleaved.

Each run is a fresh process with ``PYTHONPATH=<tree>/src`` and the default
``TETHER_JIT`` (``auto``), so imports and numba's start-up (if a run loads it) count.
The first pair only warms the file cache and is not kept.

    python benchmarks/bench_run_cpu.py --old-root /work/main [--scenario silent_demo]
        [--pairs 3] [--out PATH]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from tether.runfolder import machine

CODE = "import sys; from tether.cli import main; main(sys.argv[1:])"


def cpu_of_run(root: Path, scenario: str) -> float:
    """User + system CPU seconds of one ``tether run`` process with ``root``'s code."""
    env = dict(os.environ, PYTHONPATH=str(root / "src"))
    env.pop("TETHER_JIT", None)
    with tempfile.TemporaryDirectory() as tmp:
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        cmd = [sys.executable, "-c", CODE, "run", scenario, "--no-figures", "--out", tmp]
        subprocess.run(cmd, cwd=root, env=env, capture_output=True, check=True)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old-root", type=Path, required=True)
    ap.add_argument("--new-root", type=Path, default=Path(__file__).resolve().parents[1])
    ap.add_argument("--scenario", default="silent_demo")
    ap.add_argument("--pairs", type=int, default=3)
    ap.add_argument("--out", type=Path)
    a = ap.parse_args()
    trees = {"old": a.old_root.resolve(), "new": a.new_root.resolve()}
    res: dict[str, list[float]] = {"old": [], "new": []}
    for i in range(a.pairs + 1):
        for side in ("old", "new") if i % 2 == 0 else ("new", "old"):
            cpu = cpu_of_run(trees[side], a.scenario)
            if i:
                res[side].append(cpu)
            print(f"{side} {cpu:.2f} s", flush=True)
    out = {"machine": machine(), "scenario": a.scenario,
           "trees": {k: str(v) for k, v in trees.items()}, "cpu_s": res,
           "median_cpu_s": {k: statistics.median(v) for k, v in res.items() if v}}  # fmt: skip
    print(json.dumps(out))
    if a.out:
        a.out.write_text(json.dumps(out, indent=1) + "\n")


if __name__ == "__main__":
    main()
