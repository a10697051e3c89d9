"""Seeing a run: sizes and times of ``tether view``, ``animate`` and ``export``.

Each scenario is simulated with ``tether run --no-figures`` into a temporary folder, then
each command runs on that folder with its defaults in a fresh process, as a user runs it:
``view`` (``replay.html``: size, recorded steps kept), ``animate`` (``animation.gif``:
size, frames counted with Pillow), ``export --format mcap`` and ``--format rosbag2``
(size of the file, of the folder). Times are the processor time of the whole command
(Python's start-up, reading the folder, rebuilding the world included; on an idle
machine about its wall time).
"""

from __future__ import annotations

import re
import subprocess
import tempfile
from pathlib import Path

from suite.core import ROOT, Line, command, row, tether_cli
from suite.report import register_table

SCENARIOS = ("silent_demo", "connectivity_town", "recurrent_demo")


def size_mb(path: Path) -> float:
    if path.is_dir():
        return sum(p.stat().st_size for p in path.rglob("*") if p.is_file()) / 1e6
    return path.stat().st_size / 1e6


def describe(run_dir: Path) -> dict:
    """What the table's first column says about the run (read in-process, not timed)."""
    from tether.viewing.runfolder import load_run

    run = load_run(run_dir)
    grid = run.grid
    return {
        "robots": run.n_robots,
        "dim": run.dim,
        "steps": int(run.summary.get("steps", run.frame_steps[-1])),
        "recorded_steps": run.n_frames,
        "map_cells": list(grid.shape) if grid is not None and run.dim == 2 else None,
    }


def measure(scenario: str, folder: Path) -> dict:
    from PIL import Image

    cli = tether_cli()
    run_dir = folder / scenario
    command([*cli, "run", scenario, "--out", str(run_dir), "--no-figures"])
    rec: dict = {"scenario": scenario, "run": describe(run_dir)}
    html = run_dir / "replay.html"
    said = subprocess.run([*cli, "view", str(run_dir), "--out", str(html)], cwd=ROOT,
                          capture_output=True, text=True, check=True).stdout  # fmt: skip
    kept = re.search(r"1\s+in\s+(\d+)\s+recorded", said)
    _, cpu = command([*cli, "view", str(run_dir), "--out", str(html)])
    rec["view"] = {"mb": size_mb(html), "cpu_s": cpu, "stride": int(kept[1]) if kept else 1}
    _, cpu = command([*cli, "animate", str(run_dir)])
    gif = run_dir / "animation.gif"
    with Image.open(gif) as img:
        rec["animate"] = {"frames": int(img.n_frames), "mb": size_mb(gif), "cpu_s": cpu}
    for fmt in ("mcap", "rosbag2"):
        out = run_dir / ("run.mcap" if fmt == "mcap" else "rosbag2")
        _, cpu = command([*cli, "export", str(run_dir), "--format", fmt, "--out", str(out)])
        rec[fmt] = {"mb": size_mb(out), "cpu_s": cpu}
    return rec


@row("viewing", "seeing a run: tether view, animate and export", full_only=True)
def viewing(quick: bool) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        per = [measure(s, Path(tmp)) for s in SCENARIOS]
    lines = [
        Line(f"tether view {p['scenario']} (whole command, CPU)", "s", p["view"]["cpu_s"],
             extra={"mb": p["view"]["mb"]})
        for p in per
    ]  # fmt: skip
    return {"lines": lines, "details": {"runs": per}}


def _label(r: dict) -> str:
    run = r["run"]
    where = f"{run['map_cells'][0]} x {run['map_cells'][1]} map" if run["map_cells"] else (
        f"{run['dim']}-D")  # fmt: skip
    if run["recorded_steps"] < run["steps"]:
        steps = f"{run['recorded_steps']:,} recorded steps"
    else:
        steps = f"{run['steps']:,} steps"
    return f"`{r['scenario']}` ({run['robots']} robots, {where}, {steps})"


@register_table("viewing")
def table_viewing(doc: dict) -> str:
    out = [
        "| run | `tether view` | `tether animate` (GIF, defaults: 720 px, at most 200 "
        "frames) | `tether export` mcap / rosbag2 |",
        "| --- | --- | --- | --- |",
    ]
    for r in doc["rows"].get("viewing", {}).get("details", {}).get("runs", []):
        v, a, m, b = r["view"], r["animate"], r["mcap"], r["rosbag2"]
        kept = "every step kept" if v["stride"] == 1 else f"1 in {v['stride']} steps"
        out.append(
            f"| {_label(r)} | {v['mb']:.2f} MB, {v['cpu_s']:.1f} s, {kept} | {a['frames']} "
            f"frames, {a['mb']:.2f} MB, {a['cpu_s']:.1f} s | {m['mb']:.2f} MB, "
            f"{m['cpu_s']:.1f} s / {b['mb']:.2f} MB, {b['cpu_s']:.1f} s |"
        )
    return "\n".join(out)
