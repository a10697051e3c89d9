"""Trial by trial, do two Fig. 9 campaigns (two ``benchmarks/fig9.py --runs`` folders)
give the same summaries?

For every scene folder both runs have, the trials of ``sweep.parquet`` are matched by
team size and configuration seed, and every summary column the two share (targets,
times, distances, lambda2, collisions, ...) is compared exactly; wall-clock columns are
left out. Prints, per scene, the matched trials, how many are identical, and each
trial that differs with its first differing columns. Use it to check that a code change
left a campaign's results unchanged, or that a re-run repeats a documented one.

Usage::

    python benchmarks/compare_campaigns.py RUNS_A RUNS_B [--scenes empty town office]
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import pyarrow.parquet as pq

#: columns that measure the machine, not the trial
SKIP = ("wall_time_s", "run_dir")


def _same(a: object, b: object) -> bool:
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return a == b


def compare_scene(a: Path, b: Path) -> tuple[int, int, list[str]]:
    """(matched trials, identical trials, lines for the trials that differ)."""
    rows_a = pq.read_table(a / "sweep.parquet").to_pylist()
    rows_b = {(r["param:team.n_robots"], r["seed"]): r
              for r in pq.read_table(b / "sweep.parquet").to_pylist()}  # fmt: skip
    matched = same = 0
    lines = []
    for ra in rows_a:
        key = (ra["param:team.n_robots"], ra["seed"])
        rb = rows_b.get(key)
        if rb is None:
            continue
        matched += 1
        cols = [c for c in ra if c in rb and not any(c.startswith(s) for s in SKIP)]
        diff = [c for c in cols if not _same(ra[c], rb[c])]
        if diff:
            shown = ", ".join(f"{c}: {ra[c]!r} / {rb[c]!r}" for c in diff[:3])
            lines.append(f"  N = {key[0]}, seed {key[1]}: {shown}")
        else:
            same += 1
    return matched, same, lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("runs_a", type=Path)
    ap.add_argument("runs_b", type=Path)
    ap.add_argument("--scenes", nargs="+", default=["empty", "town", "office"])
    a = ap.parse_args()
    for scene in a.scenes:
        if not ((a.runs_a / scene / "sweep.parquet").exists()
                and (a.runs_b / scene / "sweep.parquet").exists()):  # fmt: skip
            print(f"{scene}: not in both")
            continue
        matched, same, lines = compare_scene(a.runs_a / scene, a.runs_b / scene)
        print(f"{scene}: {matched} trials in both, {same} identical, {matched - same} differ")
        if lines:
            print("\n".join(lines))


if __name__ == "__main__":
    main()
