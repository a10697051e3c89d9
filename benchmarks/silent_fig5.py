"""Figs. 4 and 5 of the no-communication paper re-made: the table and figures of the silent page.

Runs (resumably) the sweep of ``scenarios/silent_paper.yaml`` (d0 in {5, 8, 11}, seed 0),
prints the Markdown table of ``docs/explanation/silent.md`` (steps to the goal, links min / max,
connected at every step, collisions), writes ``benchmarks/results/silent_fig5.json`` and
copies the sweep's links figure and the snapshot of ``tether run silent_paper``
(d0 = 11) to ``docs/figures/``::

    python benchmarks/silent_fig5.py [--runs runs/silent_fig5]
"""

from __future__ import annotations

import argparse
import json
import shutil
from pathlib import Path

import pyarrow.parquet as pq

from tether.config import load_scenario
from tether.experiments.sweep import run_sweep
from tether.runfolder import machine
from tether.runner import run

ROOT = Path(__file__).resolve().parents[1]
SCENARIO = ROOT / "src" / "tether" / "scenarios" / "silent_paper.yaml"
FIGURES = ROOT / "docs" / "figures"


def table(rows: list[dict]) -> str:
    lines = [
        "| d0 | steps to the goal | links (min / max) | connected at every step | collisions |",
        "| --- | --- | --- | --- | --- |",
    ]
    for r in sorted(rows, key=lambda r: r["param:strategy.params.d0_m"]):
        steps = f"{r['steps']:,}" if r["leader_reached_goal"] else f"not reached ({r['steps']:,})"
        lines.append(
            f"| {r['param:strategy.params.d0_m']:g} | {steps} | {r['min_links']} / "
            f"{r['max_links']} | {'yes' if r['connected_all_steps'] else 'no'} | "
            f"{r['collisions']} |"
        )
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", type=Path, default=ROOT / "runs" / "silent_fig5")
    ap.add_argument(
        "--out", type=Path, default=ROOT / "benchmarks" / "results" / "silent_fig5.json"
    )
    a = ap.parse_args()
    scenario = load_scenario(SCENARIO)
    result = run_sweep(scenario, a.runs, seeds=1, progress=print)
    rows = pq.read_table(result.table).to_pylist()
    md = table(rows)
    print(md)
    keep = ("steps", "leader_reached_goal", "min_links", "max_links", "connected_all_steps",
            "collisions", "min_distance_m", "wall_time_s")  # fmt: skip
    out = {
        "machine": machine(),
        "command": "python benchmarks/silent_fig5.py",
        "rows": [
            {"d0_m": r["param:strategy.params.d0_m"], **{k: r[k] for k in keep}} for r in rows
        ],  # fmt: skip
        "markdown": md,
    }
    a.out.write_text(json.dumps(out, indent=1) + "\n")
    FIGURES.mkdir(parents=True, exist_ok=True)
    shutil.copy(a.runs / "figures" / "links.png", FIGURES / "silent_fig5_links.png")
    fig4 = a.runs / "fig4"  # `tether run silent_paper` (d0 = 11, seed 0) with its figures
    if not (fig4 / "summary.json").exists():
        run(scenario, out_dir=fig4, seed=0, figures=True)
    shutil.copy(fig4 / "figures" / "snapshot.png", FIGURES / "silent_fig4_snapshot.png")
    print(f"wrote {a.out} and two figures in {FIGURES}")


if __name__ == "__main__":
    main()
