"""Exact ``steiner_tree`` of two trees and networkx's mehlhorn approximation, in turns in
one process: the paired version of issue 14's Steiner row.

The row's probe (``bench_issue14.py --rows steiner``) times each tree in its own process,
and each process's ratio moves by about +-10 % with the machine. Here the old tree's
``tether/recurrent/planning/steiner.py`` and ``steiner_kernels.py`` are loaded from
``--old-src`` beside the installed ones (the old ``steiner`` calling the old kernels),
and for each of the probe's graphs (``issue14_probes.steiner_graphs``) old, new and
mehlhorn run in turns (``--repeat`` rounds, medians). Both trees must give
the same cost and the same tree. Prints the per-graph medians and the row's headline
(median exact time over median mehlhorn time) for both trees; writes JSON.

    python benchmarks/paired_steiner.py --old-src /tmp/old/src [--repeat 7] [--out PATH]
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import statistics
import sys
import time
from pathlib import Path

os.environ.setdefault("TETHER_JIT", "on")

from networkx.algorithms.approximation import steiner_tree as nx_steiner  # noqa: E402

sys.path.insert(0, str(Path(__file__).parent))
from _machine import machine  # noqa: E402
from issue14_probes import steiner_graphs  # noqa: E402
from tether.recurrent.planning import steiner as new  # noqa: E402

HERE = Path(__file__).resolve().parent


def _load(name: str, path: Path, source: str):  # noqa: ANN202
    spec = importlib.util.spec_from_loader(name, loader=None, origin=str(path))
    module = importlib.util.module_from_spec(spec)
    module.__file__ = str(path)  # numba's cache keys on the file
    sys.modules[name] = module
    exec(compile(source, str(path), "exec"), module.__dict__)  # noqa: S102
    return module


def load_old(src: Path):  # noqa: ANN201
    """The old tree's ``steiner`` module, calling the old tree's own compiled kernels."""
    planning = src / "tether" / "recurrent" / "planning"
    kernels = planning / "steiner_kernels.py"
    _load("old_steiner_kernels", kernels, kernels.read_text())
    source = (planning / "steiner.py").read_text()
    source = source.replace("tether.recurrent.planning.steiner_kernels", "old_steiner_kernels")
    return _load("old_steiner", planning / "steiner.py", source)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old-src", type=Path, required=True)
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--out", type=Path, default=HERE / "results" / "paired_steiner.json")
    a = ap.parse_args()
    old = load_old(a.old_src)
    rows = []
    for i, n, k, g, terms in steiner_graphs(0, 12):
        before, after = old.steiner_tree(g, terms), new.steiner_tree(g, terms)
        same = before.cost == after.cost and sorted(map(sorted, before.tree.edges())) == sorted(
            map(sorted, after.tree.edges())
        )
        times: dict[str, list[float]] = {"old": [], "new": [], "mehlhorn": []}
        for _ in range(a.repeat):
            for name, call in (("old", old.steiner_tree), ("new", new.steiner_tree)):
                t0 = time.perf_counter()
                call(g, terms)
                times[name].append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            nx_steiner(g, terms, method="mehlhorn")
            times["mehlhorn"].append(time.perf_counter() - t0)
        row = {"graph": i, "vertices": n, "terminals": k, "same_tree": same}
        row.update({f"{name}_s": statistics.median(v) for name, v in times.items()})
        rows.append(row)
        print(f"graph {i:2d} (n {n}, k {k}): old {row['old_s'] * 1e3:6.2f}  new "
              f"{row['new_s'] * 1e3:6.2f}  mehlhorn {row['mehlhorn_s'] * 1e3:6.2f} ms"
              f"{'' if same else '  TREES DIFFER'}")  # fmt: skip
    approx = statistics.median(r["mehlhorn_s"] for r in rows)
    out = {
        "machine": machine(),
        "old_src": str(a.old_src),
        "rows": rows,
        "old_over_mehlhorn": statistics.median(r["old_s"] for r in rows) / approx,
        "new_over_mehlhorn": statistics.median(r["new_s"] for r in rows) / approx,
    }
    print(f"median exact / median mehlhorn: old {out['old_over_mehlhorn']:.3f}, "
          f"new {out['new_over_mehlhorn']:.3f}")  # fmt: skip
    a.out.write_text(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
