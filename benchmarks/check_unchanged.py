"""Fingerprint every built-in scenario's run, to show that a refactor changed nothing.

    python benchmarks/check_unchanged.py save  /tmp/fingerprints.json [SCENARIO ...]
    python benchmarks/check_unchanged.py check /tmp/fingerprints.json [SCENARIO ...]

``save`` runs each built-in scenario with its own seed (no figures) and stores, per
scenario, the summary (without wall-clock times and provenance), the SHA-256 of every
Parquet file and of every column of it, and the events as rows. ``check`` runs them
again with the code on ``PYTHONPATH`` and compares: summary values present in both,
every column present in both (a refactor may add columns), and whole files where the
column sets are equal (byte-identical Parquet). Run it from the repository root (the
real-map scenarios read ``../shared/maps``). ``save`` never overwrites a file; a missing
file or an unknown scenario is a one-line error (exit code 2); ``check`` exits 1 when a
run differs.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import pyarrow.parquet as pq

from tether.config import builtin_scenarios
from tether.runner import run

VOLATILE = {"wall_time_s", "cpu_time_s", "provenance", "timing_s", "planning_time_mean_s",
            "planning_time_max_s", "planning_times_s", "planning_time_total_s"}  # fmt: skip


VOLATILE_COLUMNS = {"planning_time_s", "solver_time_s"}  # wall-clock times in events


def _sha(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()[:16]


def fingerprint(name: str) -> dict[str, Any]:
    with tempfile.TemporaryDirectory() as tmp:
        tic = time.perf_counter()
        outcome = run(name, out_dir=Path(tmp) / "run", figures=False)
        wall = time.perf_counter() - tic
        out: dict[str, Any] = {
            "wall_s": round(wall, 2),
            "summary": {k: v for k, v in outcome.summary.items() if k not in VOLATILE},
            "files": {},
            "columns": {},
        }
        for f in sorted(outcome.path.glob("*.parquet")):
            out["files"][f.name] = _sha(f.read_bytes())
            table = pq.read_table(f)
            out["columns"][f.name] = {
                c: _sha(json.dumps(table.column(c).to_pylist(), default=str).encode())
                for c in table.column_names
            }
            if f.name == "events.parquet":
                rows = table.to_pylist()
                out["events"] = [
                    {k: v for k, v in r.items() if "time" not in k and v is not None} for r in rows
                ]
        return out


def compare(before: dict[str, Any], after: dict[str, Any]) -> list[str]:
    problems = []
    sb, sa = before["summary"], after["summary"]
    for k in sorted(set(sb) & set(sa)):
        if sb[k] != sa[k]:
            problems.append(f"summary.{k}: {sb[k]!r} -> {sa[k]!r}")
    for fname, cols in before["columns"].items():
        new = after["columns"].get(fname)
        if new is None:
            problems.append(f"{fname}: missing")
            continue
        for c, h in cols.items():
            if c in VOLATILE_COLUMNS:
                continue
            if c in new and new[c] != h:
                problems.append(f"{fname}:{c} differs")
        if (
            set(cols) == set(new)
            and not set(cols) & VOLATILE_COLUMNS
            and before["files"][fname] != after["files"][fname]
        ):
            problems.append(f"{fname}: same columns but not byte-identical")
    eb, ea = before.get("events", []), after.get("events", [])
    if len(eb) != len(ea):
        problems.append(f"events: {len(eb)} -> {len(ea)}")
    else:
        for k, (x, y) in enumerate(zip(eb, ea, strict=True)):
            common = set(x) & set(y)
            if any(x[c] != y[c] for c in common):
                problems.append(f"events[{k}] differs: {x} -> {y}")
                break
    return problems


def fail(message: str) -> None:
    """One line on stderr, exit code 2 (bad input, never a traceback)."""
    print(f"check_unchanged: {message}", file=sys.stderr)
    raise SystemExit(2)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("mode", choices=["save", "check"])
    ap.add_argument("path", type=Path, help="the fingerprints file (written by save)")
    ap.add_argument("names", nargs="*", help="built-in scenarios (default: all)")
    args = ap.parse_args(argv)
    mode, path = args.mode, args.path
    known = builtin_scenarios()
    unknown = [n for n in args.names if n not in known]
    if unknown:
        fail(f"unknown built-in scenario(s) {', '.join(unknown)}; `tether list` names them")
    names = args.names or known
    if mode == "save":
        if path.exists():
            fail(f"{path} exists; give a new file (save never overwrites)")
        result = {}
        for name in names:
            result[name] = fingerprint(name)
            print(f"{name}: {result[name]['wall_s']} s", flush=True)
        path.write_text(json.dumps(result, indent=1, default=str) + "\n")
        return
    if not path.is_file():
        fail(f"{path}: no such fingerprints file; make one with `save`")
    before = json.loads(path.read_text())
    bad = 0
    for name in names:
        if name not in before:
            print(f"{name}: not in {path}, skipped")
            continue
        after = json.loads(json.dumps(fingerprint(name), default=str))
        problems = compare(before[name], after)
        bad += bool(problems)
        print(f"{name}: {'same' if not problems else 'DIFFERENT'}", flush=True)
        for p in problems[:20]:
            print(f"   {p}")
    sys.exit(1 if bad else 0)


if __name__ == "__main__":
    main()
