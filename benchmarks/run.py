"""Run tether's benchmark suite: every performance row of the docs, one results file.

    python benchmarks/run.py                    # every row (about 20 min on 2 cores)
    python benchmarks/run.py --quick            # every row small, nothing written (~3 min)
    python benchmarks/run.py --only steiner_steinlib fiedler_small
    python benchmarks/run.py --docs             # every row, then the docs' tables
    python benchmarks/run.py --render           # the docs' tables from the results file
    python benchmarks/run.py --list             # the rows

A full run writes ``benchmarks/results/<machine>.json`` (``--out`` to choose): rows
that ran replace their earlier results there, the others are kept. ``--quick`` runs
every row at a small size to check that it works and writes only where ``--out``
says. Each row's lines state their goal, the peer timed in the same run, our steady
state and the warm-up (first calls: imports, numba's compilation or cache load) apart.
See docs/performance.md.
"""

from __future__ import annotations

import argparse
import datetime as dt
import os
import subprocess
import sys
import time
import traceback
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # one BLAS thread: small matrices, serial kernels

sys.path.insert(0, str(Path(__file__).resolve().parent))

import suite.rows  # noqa: E402, F401  (registers every row)
from suite import report  # noqa: E402
from suite.core import ROOT, ROWS  # noqa: E402


def machine() -> dict:
    from tether.runfolder import machine as base

    info = base()
    for pkg in ("numba", "networkx", "highspy", "pyscipopt", "mpe2"):
        try:
            info[pkg] = version(pkg)
        except PackageNotFoundError:
            info[pkg] = None
    info["tether_jit"] = os.environ.get("TETHER_JIT", "auto")
    return info


def prepare() -> None:
    """Fill numba's cache before anything is timed (a no-op when it is warm already), so
    that no row's child process compiles; ``kernels_compile`` times compilation apart."""
    print("filling numba's cache (python -m tether.kernel_cache) ...", flush=True)
    env = dict(os.environ, TETHER_JIT="1")
    subprocess.run([sys.executable, "-m", "tether.kernel_cache"], env=env, check=True)


def parse(argv: list[str] | None) -> argparse.Namespace:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="+", metavar="ROW", help="run these rows (see --list)")
    ap.add_argument("--quick", action="store_true", help="small sizes; writes only to --out")
    ap.add_argument("--out", type=Path, help="results file (default: results/<machine>.json)")
    ap.add_argument("--docs", action="store_true", help="then re-make the docs' tables")
    ap.add_argument("--render", action="store_true", help="only re-make the docs' tables")
    ap.add_argument("--list", action="store_true", help="print the rows and exit")
    args = ap.parse_args(argv)
    unknown = sorted(set(args.only or []) - set(ROWS))
    if unknown:
        ap.error(f"unknown row(s) {', '.join(unknown)}; --list shows the rows")
    if args.quick and args.docs:
        ap.error("--docs takes the numbers of a full run, not of --quick")
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse(argv)
    if args.list:
        for row in ROWS.values():
            print(f"{row.name:22s} {row.title}{'  (full run only)' if row.full_only else ''}")
        return 0
    out = args.out or report.RESULTS / f"{report.machine_name()}.json"
    if args.render:
        doc = report.load(out)
        doc["rows"] = {k: doc["rows"][k] for k in ROWS if k in doc["rows"]}
        report.save(out, doc)
        for page in report.rewrite_pages(out):
            print(f"rewrote {page}")
        return 0
    names = args.only or list(ROWS)
    doc = report.load(out) if not args.quick or args.out else {"rows": {}}
    doc["machine"] = machine()
    doc["command"] = "python benchmarks/run.py" + (" --quick" if args.quick else "")
    failed = []
    if not args.quick:
        prepare()
    for name in names:
        row = ROWS[name]
        if args.quick and row.full_only:
            print(f"{name}: skipped by --quick")
            continue
        print(f"{name}: {row.title} ...", flush=True)
        load0, t0 = os.getloadavg()[0], time.perf_counter()
        try:
            result = row.run(args.quick)
        except Exception:  # a broken row is reported, the others still run
            failed.append(name)
            traceback.print_exc()
            continue
        doc["rows"][name] = {
            "title": row.title,
            "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
            "quick": args.quick,
            "seconds": time.perf_counter() - t0,
            "load_average": [load0, os.getloadavg()[0]],
            "lines": [line.as_dict() for line in result["lines"]],
            "details": result.get("details", {}),
        }
        if result.get("skipped"):
            doc["rows"][name]["skipped"] = result["skipped"]
            print(f"  not measured: {result['skipped']}")
        for line in result["lines"]:
            ratio = f", {line.ratio:.3g}x {line.peer}" if line.ratio is not None else ""
            met = {True: "met", False: "NOT met", None: "no goal"}[line.met]
            print(f"  {line.label}: {report.with_unit(line.ours, line.unit)}{ratio} ({met})")
        if not args.quick or args.out:
            doc["rows"] = {k: doc["rows"][k] for k in ROWS if k in doc["rows"]}
            report.save(out, doc)
    if not args.quick or args.out:
        print(f"wrote {out.relative_to(ROOT) if out.is_relative_to(ROOT) else out}")
    if args.docs:
        for page in report.rewrite_pages(out):
            print(f"rewrote {page}")
    if failed:
        print(f"failed rows: {', '.join(failed)}", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
