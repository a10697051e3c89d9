"""Print issue 14's table (goal, old, main, new, met?) from bench_issue14.py's JSON.

Rows come from ``results/issue14.json`` (old 4cef8e4, main, new in one run); rows it
lacks from ``results/issue14_first_run.json`` (old against main, whose code for those
rows perf2 did not change, so main's number stands for new too).

    python benchmarks/issue14_table.py [--final PATH] [--first PATH] [--update PATH ...]

``--update`` takes later runs of some rows (``bench_issue14.py --old-root <main then>``,
e.g. ``results/issue14_eig.json``): their old tree (main at that time) fills the main
column, their new tree the new column; the 4cef8e4 column stays the first file's.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

HERE = Path(__file__).resolve().parent

LABELS = {
    "step35_free": ("connectivity-force step, 35 robots, free 3-D", "us", 1e6),
    "step35_town": ("the same, 35 robots in the town", "us", 1e6),
    "step1000_free": ("the same, 1,000 robots free", "ms", 1e3),
    "step10000_free": ("the same, 10,000 robots free", "ms", 1e3),
    "silent10000": ("silent step, 10,000 robots, occlusion on", "steps/s", 1.0),
    "silent20": ("silent step, 20 robots", "ms", 1.0),
    "placement100k": ("random connected placement, 100,000 robots", "s", 1.0),
    "placement1000": ("(placement, 1,000 robots: old vs new)", "s", 1.0),
    "steiner": ("exact steiner_tree / networkx mehlhorn (median ratio)", "x", 1.0),
    "ilp": ("exact configuration ILP, SCIP median (max)", "s", 1.0),
    "recurrent_grass": ("recurrent_grass 900 steps, CPU time", "s", 1.0),
}


def cell(row: dict, side: str, scale: float) -> str:
    if side not in row:
        return "-"
    value = row[side] * scale
    text = f"{value:,.0f}" if value >= 1000 else f"{value:.3g}"
    extra = row.get(f"{side}_extra") or {}
    if "scip_max_s" in extra:
        text += f" ({extra['scip_max_s']:.3g})"
    return text


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--final", type=Path, default=HERE / "results" / "issue14.json")
    ap.add_argument("--first", type=Path, default=HERE / "results" / "issue14_first_run.json")
    ap.add_argument("--update", type=Path, nargs="*", default=[])
    a = ap.parse_args()
    final = json.loads(a.final.read_text())["rows"] if a.final.exists() else {}
    for path in a.update:  # later runs: their "old" is main at the time, "new" the branch
        later = json.loads(path.read_text())
        for key, row in later["rows"].items():
            merged = dict(final.get(key, {}))
            merged.update({k: v for k, v in row.items() if not k.startswith("old")})
            merged["main"], merged["main_extra"] = row["old"], row.get("old_extra")
            merged["trees"] = later.get("trees", {})
            final[key] = merged
    first = json.loads(a.first.read_text())["rows"] if a.first.exists() else {}
    print("| work | goal | old (4cef8e4) | main (per row, below) | new | met? |")
    print("| --- | --- | --- | --- | --- | --- |")
    own: dict[str, dict] = {}
    for key, (label, unit, scale) in LABELS.items():
        if key in final:
            row, main_side = final[key], "main"
        elif key in first:
            row, main_side = first[key], "new"
        else:
            continue
        goal = f"{row['goal_sense']} {row['goal'] * scale:.3g} {unit}"
        new = cell(row, "new", scale)
        main_ = cell(row, main_side, scale)
        met = "yes" if row["met"] else "no"
        if "trees" in row:  # re-measured later with other trees (their hashes below)
            label += " *"
            own[key] = row["trees"]
        print(f"| {label} | {goal} | {cell(row, 'old', scale)} | {main_} | {new} | {met} |")
    for key, trees in own.items():
        names = ", ".join(f"{n} {t['git_hash'][:7]}" for n, t in trees.items())
        print(f"\n\\* {key}: {names}")


if __name__ == "__main__":
    main()
