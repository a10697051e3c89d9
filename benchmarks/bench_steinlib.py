"""The exact Steiner tree on SteinLib's set B: cost against the published optimum, and time.

Reads the 18 instances of ``tests/data/steinlib`` (Beasley's set B, 50-100 vertices,
9-50 terminals; optima from the README table there) with
:func:`tether.graph.steinlib.read_stp` and runs
:func:`tether.recurrent.planning.steiner.steiner_tree` on every instance with at most
``--max-terminals`` terminals: the compiled kernel (if numba is installed) and the
reference numpy path up to ``--reference-max-terminals``. Dreyfus-Wagner's work grows
as ``3^k`` for ``k`` terminals, so 19 terminals take 4-5 s compiled and the 25-terminal
instances are out of reach (about 3^6 = 729 times the 19-terminal work, and tables of
about 19 GiB, which ``steiner_tree`` refuses). Each solve is timed once (wall clock and
process CPU time); the kernel's first call (numba import and cache load, or compilation
on a cold cache) is timed apart, on
b01, before the others.

Usage::

    python benchmarks/bench_steinlib.py [--max-terminals 19] [--reference-max-terminals 17]
        [--out benchmarks/results/steinlib_b.json]

Prints a Markdown table and writes the JSON (machine, load average, settings, per
instance: nodes, edges, terminals, optimum, our cost, seconds).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

from tether import jit
from tether.graph.steinlib import read_stp
from tether.recurrent.planning.steiner import MAX_TABLE_BYTES, steiner_tree, table_bytes

HERE = Path(__file__).resolve().parent
DATA = HERE.parent / "tests" / "data" / "steinlib"
OUT = HERE / "results" / "steinlib_b.json"


def optima() -> dict[str, int]:
    """name -> optimum, from the table of ``tests/data/steinlib/README.md``."""
    rows = re.findall(r"^\| (b\d\d) \| \d+ \| \d+ \| \d+ \| (\d+) \|$",
                      (DATA / "README.md").read_text(), flags=re.MULTILINE)  # fmt: skip
    return {name: int(opt) for name, opt in rows}


def machine_info() -> dict[str, Any]:
    from importlib.metadata import version

    sys.path.insert(0, str(HERE))
    from _machine import machine  # benchmarks/_machine.py

    info = machine()
    for pkg in ("networkx", "numba"):
        try:
            info[pkg] = version(pkg)
        except Exception:  # noqa: BLE001 - numba is optional
            info[pkg] = None
    return info


def git_state() -> dict[str, Any]:
    """The commit of this checkout and whether its working tree had changes."""

    def git(*cmd: str) -> str:
        return subprocess.run(["git", *cmd], cwd=HERE, capture_output=True, text=True).stdout

    return {"commit": git("rev-parse", "HEAD").strip(), "dirty": bool(git("status", "--porcelain"))}


def solve(graph, terminals, kernel: bool) -> dict[str, Any]:
    """One timed call of ``steiner_tree`` with the kernel on or off."""
    with jit.using(kernel):
        wall, cpu = time.perf_counter(), time.process_time()
        cost, tree = steiner_tree(graph, terminals)
        wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
    weight = sum(graph.edges[e]["weight"] for e in tree.edges)
    return {"cost": cost, "tree_weight": weight, "wall_s": round(wall, 4), "cpu_s": round(cpu, 4)}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n", 1)[0])
    ap.add_argument("--max-terminals", type=int, default=19)
    ap.add_argument("--reference-max-terminals", type=int, default=17)
    ap.add_argument("--out", type=Path, default=OUT)
    args = ap.parse_args(argv)

    best = optima()
    kernel = jit.available()
    load = [os.getloadavg()[0]]
    first_call = None
    if kernel:
        graph, terminals = read_stp(DATA / "b01.stp")
        first_call = solve(graph, terminals, True)
    rows = []
    for path in sorted(DATA.glob("b*.stp")):
        graph, terminals = read_stp(path)
        k = len(terminals)
        row: dict[str, Any] = {
            "name": path.stem,
            "nodes": graph.number_of_nodes(),
            "edges": graph.number_of_edges(),
            "terminals": k,
            "optimum": best[path.stem],
        }
        need = table_bytes(k, graph.number_of_nodes())  # the graphs are connected
        if k > args.max_terminals:
            row["skipped"] = f"more than {args.max_terminals} terminals"
        elif need > MAX_TABLE_BYTES:
            row["skipped"] = f"tables of {need / 1024**3:.1f} GiB (MAX_TABLE_BYTES)"
        else:
            if kernel:
                row["kernel"] = solve(graph, terminals, True)
            if k <= args.reference_max_terminals or not kernel:
                row["reference"] = solve(graph, terminals, False)
            runs = [row[m] for m in ("kernel", "reference") if m in row]
            row["cost"] = runs[0]["cost"]
            row["optimal"] = all(r["cost"] == r["tree_weight"] == row["optimum"] for r in runs)
        rows.append(row)
        print(_line(row), flush=True)
    load.append(os.getloadavg()[0])
    result = {
        "benchmark": "exact steiner_tree on SteinLib set B",
        "command": "python benchmarks/bench_steinlib.py " + " ".join(argv or sys.argv[1:]),
        "machine": machine_info(),
        "git": git_state(),
        "load_average_1min": load,
        "settings": vars(args) | {"out": str(args.out), "kernel": kernel},
        "kernel_first_call_b01": first_call,
        "instances": rows,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    print(_table(rows, first_call))
    print(f"wrote {args.out}")
    return 0 if all(r.get("optimal", True) for r in rows) else 1


def _seconds(run: dict | None) -> str:
    return "-" if run is None else f"{run['wall_s']:.3g} ({run['cpu_s']:.3g})"


def _line(row: dict) -> str:
    if "skipped" in row:
        return f"{row['name']}: {row['terminals']} terminals, skipped"
    kernel, reference = _seconds(row.get("kernel")), _seconds(row.get("reference"))
    return (
        f"{row['name']}: cost {row['cost']:g}, optimum {row['optimum']}; seconds (CPU): "
        f"kernel {kernel}, reference {reference}"
    )


def _table(rows: list[dict], first_call: dict | None) -> str:
    lines = [
        "| instance | nodes | edges | terminals | optimum | our cost | kernel s (CPU) "
        "| reference s (CPU) |",
        "| --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for r in rows:
        cost = "not run" if "skipped" in r else f"{r['cost']:g}"
        lines.append(
            f"| {r['name']} | {r['nodes']} | {r['edges']} | {r['terminals']} | {r['optimum']} "
            f"| {cost} | {_seconds(r.get('kernel'))} | {_seconds(r.get('reference'))} |"
        )
    if first_call is not None:
        lines.append(f"\nkernel's first call (b01): {_seconds(first_call)} s")
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
