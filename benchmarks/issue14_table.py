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


def _source(path: Path, data: dict) -> str:
    """One footnote: the JSON, its trees (old -> new), date, clock and conditions."""
    trees = data.get("trees") or {}
    names = " -> ".join(f"{n} {t.get('git_hash', '')[:7]}" for n, t in trees.items())
    date = str((data.get("machine") or {}).get("date", ""))[:10]
    cond = data.get("conditions") or ""
    clock = data.get("clock", "cpu")
    return f"`results/{path.name}`: {names or 'old -> new'}, {date}, {clock} clock; {cond}"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--final", type=Path, default=HERE / "results" / "issue14.json")
    ap.add_argument("--first", type=Path, default=HERE / "results" / "issue14_first_run.json")
    ap.add_argument("--update", type=Path, nargs="*", default=[])
    a = ap.parse_args()
    first = json.loads(a.first.read_text())["rows"] if a.first.exists() else {}
    base = json.loads(a.final.read_text()) if a.final.exists() else {"rows": {}}
    rows: dict[str, dict] = {k: dict(v, main=v.get("main", v.get("new"))) for k, v in first.items()}
    notes: list[str] = [_source(a.first, json.loads(a.first.read_text()))] if first else []
    source = dict.fromkeys(rows, 1)
    for path, data in [(a.final, base)] + [(p, json.loads(p.read_text())) for p in a.update]:
        if not data["rows"]:
            continue
        notes.append(_source(path, data))
        for key, row in data["rows"].items():
            merged = dict(rows.get(key, {}))
            if path == a.final:  # the first full run: old 4cef8e4, main, new
                merged.update(row)
            else:  # a later run: its old tree is main at that time, its new the branch
                merged.update({k: v for k, v in row.items() if not k.startswith("old")})
                if "old" in row:  # (a row the old tree cannot run keeps the main before)
                    merged["main"], merged["main_extra"] = row["old"], row.get("old_extra")
            rows[key] = merged
            source[key] = len(notes)
    print("| work | goal | old (4cef8e4) | before (the run's old tree) | new | met? | run |")
    print("| --- | --- | --- | --- | --- | --- | --- |")
    for key, (label, unit, scale) in LABELS.items():
        if key not in rows:
            continue
        row = rows[key]
        if "old" not in row and "old" in first.get(key, {}):
            row["old"], row["old_extra"] = first[key]["old"], first[key].get("old_extra")
        goal = f"{row['goal_sense']} {row['goal'] * scale:.3g} {unit}"
        met = "yes" if row["met"] else "no"
        print(
            f"| {label} | {goal} | {cell(row, 'old', scale)} | {cell(row, 'main', scale)} "
            f"| {cell(row, 'new', scale)} | {met} | [{source[key]}] |"
        )
    print()
    for i, note in enumerate(notes, 1):
        print(f"[{i}] {note}\n")


if __name__ == "__main__":
    main()
