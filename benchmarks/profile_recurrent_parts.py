"""Per-part CPU time of a recurrent scenario run (inclusive), by wrapping its functions.

    TETHER_JIT=on python benchmarks/profile_recurrent_parts.py recurrent_grass

Each listed function is replaced by a wrapper that adds its ``time.process_time`` to a
total (nested parts count in their callers too); then the scenario runs once without
figures. The garbage collector's passes are timed too (``gc.callbacks``): they count in
whichever part allocates when one starts. Used for the ``recurrent_grass`` profile in
docs/performance.md.
"""

import collections
import functools
import gc
import importlib
import sys
import tempfile
import time
from pathlib import Path

T = collections.defaultdict(float)
N = collections.Counter()
GC = {"start": 0.0, "total": 0.0, "passes": 0}


def _gc_timer(phase, info):
    if phase == "start":
        GC["start"] = time.process_time()
    else:
        GC["total"] += time.process_time() - GC["start"]
        GC["passes"] += 1


def wrap(modname, qual):
    mod = importlib.import_module(modname)
    obj = mod
    parts = qual.split(".")
    for p in parts[:-1]:
        obj = getattr(obj, p)
    f = getattr(obj, parts[-1])
    if isinstance(f, staticmethod):
        f = f.__func__

    @functools.wraps(f)
    def g(*a, **k):
        t = time.process_time()
        try:
            return f(*a, **k)
        finally:
            T[qual] += time.process_time() - t
            N[qual] += 1

    raw = obj.__dict__.get(parts[-1]) if isinstance(obj, type) else None
    setattr(obj, parts[-1], staticmethod(g) if isinstance(raw, staticmethod) else g)
    # also patch names imported elsewhere
    for m in list(sys.modules.values()):
        if m is not None and m is not mod and getattr(m, parts[-1], None) is f and len(parts) == 1:
            setattr(m, parts[-1], g)


t0 = time.process_time()
from tether.runner import run

targets = [
    ("tether.recurrent.exploration.sim", "ExplorationSim._move"),
    ("tether.recurrent.exploration.sim", "ExplorationSim._sense"),
    ("tether.recurrent.exploration.sim", "ExplorationSim._communicate"),
    ("tether.recurrent.exploration.knowledge", "Knowledge.exchange"),
    ("tether.recurrent.exploration.sim", "ExplorationSim.explored_fraction"),
    ("tether.recurrent.replanning", "RecurrentStrategy.update"),
    ("tether.recurrent.replanning", "RecurrentStrategy.plan"),
    ("tether.recurrent.replanning", "RecurrentStrategy.relaying"),
    ("tether.recurrent.exploration.sim", "ExplorationSim.coarse_known"),
    ("tether.recurrent.planning.expgraph", "GraphBuilder.build"),
    ("tether.recurrent.planning.expgraph", "GraphBuilder._edges"),
    ("tether.recurrent.planning.expgraph", "frontier_nodes"),
    ("tether.recurrent.planning.expgraph", "snap_cluster"),
    ("tether.recurrent.planning.expgraph", "window_counts"),
    ("tether.recurrent.planning.expgraph", "frontier_clusters"),
    ("tether.recurrent.planning.expgraph", "ExplorationGraph.to_networkx"),
    ("tether.recurrent.replanning", "RecurrentStrategy._distances"),
    ("tether.recurrent.replanning", "frontier_utilities"),
    ("tether.recurrent.replanning", "optimal_configuration"),
    ("tether.recurrent.planning.problem", "build"),
    ("tether.recurrent.planning.configuration", "solve_apx"),
    ("tether.recurrent.replanning", "RecurrentStrategy._deploy"),
    ("tether.recurrent.replanning", "check_configuration"),
    ("tether.recurrent.replanning", "RecurrentStrategy._bind"),
    ("tether.sim", "team_metrics"),
    ("tether.sensing.links", "link_pairs"),
]
for m, q in targets:
    try:
        wrap(m, q)
    except Exception as e:
        print("skip", m, q, e)
t1 = time.process_time()
gc.callbacks.append(_gc_timer)
with tempfile.TemporaryDirectory() as tmp:
    out = run(sys.argv[1], out_dir=Path(tmp) / "r", figures=False)
t2 = time.process_time()
gc.callbacks.remove(_gc_timer)
print(f"imports {t1 - t0:.2f} s, run {t2 - t1:.2f} s")
for _m, q in targets:
    print(f"{q:45s} {T[q]:7.2f} s  {N[q]:6d} calls")
gc_part = "garbage collector (in the parts above)"
print(f"{gc_part:45s} {GC['total']:7.2f} s  {GC['passes']:6d} passes")
