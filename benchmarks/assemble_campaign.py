"""A campaign's folder with some trials replaced by their re-runs, for ``fig9.py --no-run``.

A change that acts only on some trials (a helpers' setting re-run with
``benchmarks/rerun_helped.py``) leaves every other trial of a campaign bit for bit as it
was; the campaign under the change is then the old trials plus the re-runs. This writes
``OUT/<scene>/sweep.parquet``: the rows of ``BASE/<scene>/sweep.parquet``, each trial
that has a re-run under ``RERUNS`` (the same relative run folder, with a
``summary.json``) taking that summary's values and run folder. The tables and figure of
the assembled campaign are then ``python benchmarks/fig9.py --no-run --seeds 100 --runs
OUT --out PATH --figure PATH``.

Usage::

    python benchmarks/assemble_campaign.py BASE RERUNS OUT [--scenes empty town office]
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import pyarrow as pa
import pyarrow.parquet as pq


def assemble(base: Path, reruns: Path, out: Path) -> int:
    """Write ``out/sweep.parquet`` from one scene's ``base`` and ``reruns``; the number
    of trials replaced."""
    table = pq.read_table(base / "sweep.parquet")
    rows = table.to_pylist()
    replaced = 0
    for row in rows:
        summary_path = reruns / Path(row["run_dir"]).relative_to(base) / "summary.json"
        if not summary_path.exists():
            continue
        summary = json.loads(summary_path.read_text())
        for key in row:
            if key in summary:
                row[key] = summary[key]
        row["run_dir"] = str(summary_path.parent)
        replaced += 1
    out.mkdir(parents=True, exist_ok=True)
    pq.write_table(pa.Table.from_pylist(rows, schema=table.schema), out / "sweep.parquet")
    return replaced


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("base", type=Path, help="a finished campaign of benchmarks/fig9.py")
    ap.add_argument("reruns", type=Path, help="re-runs of some of its trials (same layout)")
    ap.add_argument("out", type=Path)
    ap.add_argument("--scenes", nargs="+", default=["empty", "town", "office"])
    a = ap.parse_args()
    for scene in a.scenes:
        n = assemble(a.base / scene, a.reruns / scene, a.out / scene)
        print(f"{scene}: {n} trials replaced by their re-runs")


if __name__ == "__main__":
    main()
