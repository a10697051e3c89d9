"""One measurement of one row of issue 14's table, run with whichever ``tether`` is importable.

Run by :mod:`bench_issue14` as ``python issue14_probes.py <probe> '<json kwargs>'`` with
``PYTHONPATH=<tree>/src`` and ``TETHER_TREE=<tree>`` (the tree's own benchmark scripts
are imported from ``<tree>/benchmarks``), so old and new code are timed by the same
driver. Prints one JSON line. Where the two trees' modules differ in name (the
pre-refactor commit 4cef8e4 has ``tether.recurrent.steiner`` where the new tree has
``tether.recurrent.planning.steiner``), both names are tried.

Timings use ``time.perf_counter``; the driver replaces it with ``time.process_time``
under ``--clock cpu`` (CPU time of this process: less sensitive to other jobs).
"""

from __future__ import annotations

import importlib
import importlib.util
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

TREE = Path(os.environ.get("TETHER_TREE", Path(__file__).resolve().parents[1]))


def _tree_script(name: str) -> Any:
    """The tree's own ``benchmarks/<name>.py`` as a module."""
    sys.path.insert(0, str(TREE / "benchmarks"))
    spec = importlib.util.spec_from_file_location(name, TREE / "benchmarks" / f"{name}.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _first_module(*names: str) -> Any:
    for name in names:
        try:
            return importlib.import_module(name)
        except ModuleNotFoundError:
            continue
    raise ModuleNotFoundError(names)


def step(world: str, n: int, repeat: int) -> dict:
    """One connectivity-force step, exact solver (the tree's bench_continuous_step.bench)."""
    import numpy as np

    from tether.world.scenes import make_scene
    from tether.world.world import World

    mod = _tree_script("bench_continuous_step")
    if world == "free":
        w = World(dim=3, bounds_m=np.array([[0.0, 0, 0], [200.0, 200.0, 10.0]]), name="free")
    else:
        w = make_scene("town", 0, size_m=(50.0, 70.0), resolution_m=0.25)
        w.name = world
    mod.timed = _batch_timed
    return mod.bench(w, n, "exact", 0, repeat)


def _batch_timed(fn, repeat: int) -> float:  # noqa: ANN001
    """Mean time of ``fn()`` over ``repeat`` calls after one untimed call, read twice.

    Replaces the scripts' per-call median: on this VM one ``time.process_time()`` costs
    about 13 us (no vDSO for CPU clocks), which a per-call reading adds to every call.
    """
    fn()
    t0 = time.perf_counter()
    for _ in range(repeat):
        fn()
    return (time.perf_counter() - t0) / repeat


def silent(n: int, steps: int) -> dict:
    """``silent`` steps (sensing with occlusion + strategy + metrics), bench_silent.bench."""
    mod = _tree_script("bench_silent")
    mod.bench(n, 2)  # first calls (imports, caches) not timed
    t0 = time.perf_counter()
    row = mod.bench(n, steps)
    # the whole loop read twice: the script reads the clock four times per step (each
    # reading ~13 us of CPU time on this VM), which the per-part sums include
    row["ms_per_step_whole"] = 1e3 * (time.perf_counter() - t0) / steps
    return row


def placement(n: int, seed: int = 1) -> dict:
    """``tether.team.random_connected``: free 2-D, spacing 8 m, separation 2 m."""
    import numpy as np

    from tether.team import random_connected
    from tether.world.world import World

    t0 = time.perf_counter()
    pos = random_connected(n, World(dim=2), np.random.default_rng(seed), 8.0, 2.0)
    return {"n_robots": int(len(pos)), "seconds": time.perf_counter() - t0}


def steiner_graphs(seed: int, count: int) -> list:
    """Random connected weighted graphs, 50-500 vertices, 3-10 terminals."""
    import networkx as nx
    import numpy as np

    rng = np.random.default_rng(seed)
    out = []
    for i in range(count):
        n = int(rng.choice([50, 100, 200, 500]))
        k = int(rng.integers(3, 11))
        g = nx.connected_watts_strogatz_graph(n, 6, 0.3, seed=int(rng.integers(1 << 30)))
        for u, v in g.edges:
            g.edges[u, v]["weight"] = float(rng.integers(1, 100))
        terms = [int(t) for t in rng.choice(n, size=k, replace=False)]
        out.append((i, n, k, g, terms))
    return out


def steiner(seed: int, count: int, repeat: int) -> dict:
    """Exact ``steiner_tree`` vs networkx's mehlhorn 2-approximation on the same graphs."""
    from networkx.algorithms.approximation import steiner_tree as nx_steiner

    exact = _first_module("tether.recurrent.planning.steiner", "tether.recurrent.steiner")
    rows = []
    for i, n, k, g, terms in steiner_graphs(seed, count):
        exact.steiner_tree(g, terms)  # first call (imports, caches) not timed
        te, ta = [], []
        for _ in range(repeat):
            t0 = time.perf_counter()
            cost, _tree = exact.steiner_tree(g, terms)
            te.append(time.perf_counter() - t0)
            t0 = time.perf_counter()
            approx = nx_steiner(g, terms, method="mehlhorn")
            ta.append(time.perf_counter() - t0)
        rows.append(
            {
                "graph": i,
                "vertices": n,
                "terminals": k,
                "exact_s": statistics.median(te),
                "mehlhorn_s": statistics.median(ta),
                "exact_cost": cost,
                "mehlhorn_cost": float(approx.size(weight="weight")),
            }
        )
    ratios = [r["exact_s"] / r["mehlhorn_s"] for r in rows]
    return {
        "rows": rows,
        "median_exact_over_mehlhorn": statistics.median(ratios),
        "median_exact_s": statistics.median(r["exact_s"] for r in rows),
        "median_mehlhorn_s": statistics.median(r["mehlhorn_s"] for r in rows),
    }


def ilp(seeds: list[int], time_limit: float) -> dict:
    """Exact configuration ILP (SCIP and HiGHS) on ``exploration_instance(seed)``.

    One untimed call per backend on a small instance first (both trees alike): the
    solver libraries' import (0.2-0.3 s each) and, where the tree has compiled kernels,
    numba's start-up and cache load are paid once per process, not by the first seed.
    Their time is reported as ``warm_up_s``.
    """
    conf = _first_module(
        "tether.recurrent.planning.configuration", "tether.recurrent.configuration"
    )
    synth = _first_module("tether.recurrent.planning.synthetic", "tether.recurrent.synthetic")
    t0 = time.perf_counter()
    small = synth.exploration_instance(0, n_vertices=70, n_edges=450, n_frontiers=12, n_robots=7)
    for backend in ("scip", "highs"):
        conf.optimal_configuration(
            small.graph, small.base, small.utilities, small.budget, "ilp", backend=backend
        )
    warm_up_s = time.perf_counter() - t0
    rows = []
    for seed in seeds:
        inst = synth.exploration_instance(seed)
        call = (inst.graph, inst.base, inst.utilities, inst.budget)
        row = {"seed": seed, "vertices": inst.graph.number_of_nodes()}
        row["edges"] = inst.graph.number_of_edges()
        for backend in ("scip", "highs"):
            t0 = time.perf_counter()
            c = conf.optimal_configuration(*call, "ilp", backend=backend, time_limit_s=time_limit)
            row[f"{backend}_s"] = time.perf_counter() - t0
            row[f"{backend}_utility"] = c.utility
            row[f"{backend}_proven_optimal"] = bool(c.proven_optimal)
        rows.append(row)
    return {"rows": rows, "warm_up_s": warm_up_s}


def run(scenario: str, sets: list[str]) -> dict:
    """``tether run <scenario> --no-figures``, CPU and wall time of the child process."""
    import resource

    with tempfile.TemporaryDirectory() as tmp:
        ru0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.time()
        cmd = [sys.executable, "-c", "from tether.cli import main; main()", "run", scenario]
        cmd += ["--no-figures", "--out", str(Path(tmp) / "r")]
        for s in sets:
            cmd += ["--set", s]
        subprocess.run(cmd, check=True, capture_output=True, cwd=TREE)
        wall = time.time() - t0
        ru1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        summary = json.loads((Path(tmp) / "r" / "summary.json").read_text())
    cpu = ru1.ru_utime - ru0.ru_utime + ru1.ru_stime - ru0.ru_stime
    return {
        "e2e_wall_s": wall,
        "e2e_cpu_s": cpu,
        "run_wall_s": summary.get("wall_time_s"),
        "steps": summary.get("steps"),
    }


if __name__ == "__main__":
    result = globals()[sys.argv[1]](**json.loads(sys.argv[2]))
    print(json.dumps(result))
