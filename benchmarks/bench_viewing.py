"""Seeing a run: sizes and wall times of ``tether view``, ``animate`` and ``export``.

The "Measured" table of docs/how-to/viewing.md. Each scenario is simulated with ``tether run``
into ``--runs`` (a fresh folder, ``--no-figures``), then each command is run on that
folder from a fresh process, as a user would, and timed by the wall clock (so the times
include starting Python, reading the folder and rebuilding the world):

* ``tether view RUN`` (``replay.html``: size, recorded steps kept),
* ``tether animate RUN`` with the defaults (``animation.gif``: size, frames counted
  with Pillow),
* ``tether export RUN --format mcap`` and ``--format rosbag2`` (size of the file, of
  the folder).

Scenarios: ``silent_demo``, ``connectivity_town``, ``recurrent_demo``; with ``--large``
also a 35-robot, 10,000-step ``silent`` run: ``silent_demo`` with
``--set team.n_robots=35 --set sim.max_steps=10000 --set
'strategy.params.trajectory.waypoints=[[0, 0], [10000, 0]]'`` (a 10 km path; its
``tether run`` takes 8 minutes or more), for which ``tether view --max-mb 2`` is timed
too. Prints the Markdown table and writes ``benchmarks/results/viewing.json`` with the
machine and the command line::

    python benchmarks/bench_viewing.py [--large] [--runs runs/bench_viewing]
        [--reuse] [--only KEY ...] [--out benchmarks/results/viewing.json]

``--reuse`` keeps a run folder that a previous call simulated (its view, animation and
export files are rewritten), e.g. to re-time the commands without the 8-minute run;
``--only KEY ...`` measures some runs (``silent_demo``, ``connectivity_town``,
``recurrent_demo``, ``silent_35x10000``) and keeps the other rows of ``--out``. Each row
records its machine, command and the 1-minute load average before and after.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

from PIL import Image

from tether.runfolder import machine
from tether.viewing.runfolder import load_run

ROOT = Path(__file__).resolve().parents[1]
LARGE_SET = [
    "team.n_robots=35",
    "sim.max_steps=10000",
    "strategy.params.trajectory.waypoints=[[0, 0], [10000, 0]]",
]
#: (key, scenario, --set overrides); the key is the run folder's name.
SCENARIOS = [
    ("silent_demo", "silent_demo", []),
    ("connectivity_town", "connectivity_town", []),
    ("recurrent_demo", "recurrent_demo", []),
]
LARGE = ("silent_35x10000", "silent_demo", LARGE_SET)


def tether_exe() -> str:
    local = Path(sys.executable).with_name("tether")
    found = str(local) if local.exists() else shutil.which("tether")
    if not found:
        sys.exit("bench_viewing: no `tether` command next to this Python or on the PATH")
    return found


def timed(args: list[str]) -> tuple[float, str]:
    """Run a command in a fresh process: (wall seconds, stdout); a failure stops the run."""
    start = time.perf_counter()
    done = subprocess.run(args, capture_output=True, text=True)
    seconds = time.perf_counter() - start
    if done.returncode != 0:
        sys.exit(f"bench_viewing: {' '.join(args)} failed:\n{done.stdout}{done.stderr}")
    return seconds, done.stdout


def size_mb(path: Path) -> float:
    if path.is_dir():
        return sum(p.stat().st_size for p in path.rglob("*") if p.is_file()) / 1e6
    return path.stat().st_size / 1e6


def gif_frames(path: Path) -> int:
    with Image.open(path) as img:
        return int(img.n_frames)


def describe(run_dir: Path) -> dict:
    """What the table's first column says about the run (read in-process, not timed)."""
    run = load_run(run_dir)
    links = run.link_offsets[1:] - run.link_offsets[:-1]
    grid = run.grid
    return {
        "n_robots": run.n_robots,
        "dim": run.dim,
        "steps": int(run.summary.get("steps", run.frame_steps[-1])),
        "recorded_steps": run.n_frames,
        "map_cells": list(grid.shape) if grid is not None and run.dim == 2 else None,
        "mean_links": float(links.mean()) if len(links) else 0.0,
        "strategy": run.summary.get("strategy"),
        "run_wall_time_s": run.summary.get("wall_time_s"),
    }


def view(tether: str, run_dir: Path, *extra: str) -> dict:
    out = run_dir / ("replay.html" if not extra else "replay_small.html")
    seconds, said = timed([tether, "view", str(run_dir), "--out", str(out), *extra])
    kept = re.search(r"1\s+in\s+(\d+)\s+recorded", said)
    return {"mb": size_mb(out), "seconds": seconds, "stride": int(kept[1]) if kept else 1}


def measure(tether: str, runs: Path, key: str, scenario: str, sets: list[str], reuse: bool):
    run_dir = runs / key
    run_s = None
    if not (reuse and (run_dir / "summary.json").exists()):
        shutil.rmtree(run_dir, ignore_errors=True)
        cmd = [tether, "run", scenario, "--out", str(run_dir), "--no-figures"]
        for s in sets:
            cmd += ["--set", s]
        print(f"{key}: tether run ...", flush=True)
        run_s, _ = timed(cmd)
    for old in ("replay.html", "replay_small.html", "animation.gif", "rosbag2"):
        target = run_dir / old
        shutil.rmtree(target) if target.is_dir() else target.unlink(missing_ok=True)
    row: dict = {"key": key, "scenario": scenario, "set": sets, "run_seconds": run_s}
    row["run"] = describe(run_dir)
    print(f"{key}: view, animate, export ...", flush=True)
    row["view"] = view(tether, run_dir)
    if key == LARGE[0]:
        row["view_max_mb_2"] = view(tether, run_dir, "--max-mb", "2")
    seconds, _ = timed([tether, "animate", str(run_dir)])
    gif = run_dir / "animation.gif"
    row["animate"] = {"frames": gif_frames(gif), "mb": size_mb(gif), "seconds": seconds}
    for fmt in ("mcap", "rosbag2"):
        out = run_dir / (f"{scenario}.mcap" if fmt == "mcap" else "rosbag2")
        seconds, _ = timed([tether, "export", str(run_dir), "--format", fmt, "--out", str(out)])
        row[fmt] = {"mb": size_mb(out), "seconds": seconds}
    return row


def label(row: dict) -> str:
    r = row["run"]
    if row["key"] == LARGE[0]:
        return (
            f"{r['n_robots']} robots, `{r['strategy']}`, {r['steps']:,} steps, "
            f"{r['mean_links']:.0f} links per step on average"
        )
    where = f"{r['map_cells'][0]} x {r['map_cells'][1]} map" if r["map_cells"] else f"{r['dim']}-D"
    recorded = "recorded steps" if r["recorded_steps"] < r["steps"] else "steps"
    n_steps = r["recorded_steps"] if r["recorded_steps"] < r["steps"] else r["steps"]
    return f"`{row['scenario']}` ({r['n_robots']} robots, {where}, {n_steps:,} {recorded})"


def mb(x: float) -> str:
    return f"{x:.2f} MB" if x < 10 else f"{x:.1f} MB" if x < 100 else f"{x:.0f} MB"


def table(rows: list[dict]) -> str:
    lines = [
        "| run | `tether view` | `tether animate` (GIF, defaults: 720 px, at most 200 "
        "frames) | `tether export` mcap / rosbag2 |",
        "| --- | --- | --- | --- |",
    ]
    for row in rows:
        v, a, m, b = row["view"], row["animate"], row["mcap"], row["rosbag2"]
        kept = "every step kept" if v["stride"] == 1 else f"1 in {v['stride']} steps"
        view_cell = f"{mb(v['mb'])}, {v['seconds']:.1f} s"
        bag = mb(b["mb"])
        if row["key"] == LARGE[0]:
            small = row["view_max_mb_2"]
            small_kept = "every step" if small["stride"] == 1 else f"1 in {small['stride']} steps"
            view_cell = (
                f"**{mb(v['mb'])}**, {v['seconds']:.1f} s, {kept}; "
                f"`--max-mb 2`: {mb(small['mb'])}, {small_kept}"
            )
            bag += " (uncompressed SQLite)"
        lines.append(
            f"| {label(row)} | {view_cell} | {a['frames']} frames, {mb(a['mb'])}, "
            f"{a['seconds']:.1f} s | {mb(m['mb'])}, {m['seconds']:.1f} s / {bag}, "
            f"{b['seconds']:.1f} s |"
        )
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--large", action="store_true", help="also the 35-robot 10,000-step run")
    ap.add_argument("--runs", type=Path, default=ROOT / "runs" / "bench_viewing")
    ap.add_argument("--reuse", action="store_true", help="keep already simulated run folders")
    keys = [s[0] for s in SCENARIOS + [LARGE]]
    ap.add_argument(
        "--only",
        nargs="+",
        choices=keys,
        help="measure these runs only; the other rows of --out are kept",
    )
    ap.add_argument("--out", type=Path, default=ROOT / "benchmarks" / "results" / "viewing.json")
    a = ap.parse_args()
    tether = tether_exe()
    a.runs.mkdir(parents=True, exist_ok=True)
    command = " ".join(["python benchmarks/bench_viewing.py", *sys.argv[1:]])
    todo = SCENARIOS + ([LARGE] if a.large else [])
    if a.only:
        todo = [s for s in SCENARIOS + [LARGE] if s[0] in a.only]
    kept = {}
    if a.only and a.out.exists():
        before = json.loads(a.out.read_text())
        kept = {r["key"]: r for r in before["results"]}
        for r in kept.values():
            r.setdefault("measured", {k: before[k] for k in ("machine", "command")})
    for key, scenario, sets in todo:
        load = os.getloadavg()
        row = measure(tether, a.runs, key, scenario, sets, a.reuse)
        row["measured"] = {
            "machine": machine(),
            "command": command,
            "load_average_1min": [load[0], os.getloadavg()[0]],
        }
        kept[key] = row
    rows = [kept[k] for k in keys if k in kept]
    md = table(rows)
    print(md)
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.out.write_text(
        json.dumps(
            {
                "machine": machine(),
                "command": command,
                "timing": "wall clock of each command in a fresh process (at the start and "
                "end of each run: the 1-minute load average)",
                "results": rows,
                "table": md,
            },
            indent=2,
        )
        + "\n"
    )
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
