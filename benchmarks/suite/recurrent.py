"""Planning of ``recurrent``: APX and the exact ILP; a whole Cluttered-map run.

* ``planning``: :func:`tether.recurrent.planning.synthetic.exploration_instance` seeds
  (about 200 vertices, 2,000 communication edges, 24-30 frontiers, 12 robots: the size
  of the paper's Sec. VII-A graphs). APX with ``delta = 4`` (median of 5 after a
  warm-up call) and the ILP with SCIP and with HiGHS (one solve each, after one untimed
  solve of a small instance per backend, which pays the solvers' imports), CPU time.
  The paper reports up to 6 s for APX and 40 s for the ILP (Gurobi); the two backends
  are each other's peer.
* ``recurrent_grass``: ``tether run recurrent_grass --no-figures`` (12 robots, 900
  steps on the Cluttered map, theta = 1, APX) as a user runs it: a fresh process, the
  default ``TETHER_JIT``; the CPU time of the whole process, the first run apart.
"""

from __future__ import annotations

import statistics
import tempfile
from pathlib import Path

from suite.core import ROOT, Line, command, cpu_clock, row, tether_cli
from suite.report import num, register_table


def _solve(call: tuple, method: str, **kw) -> tuple[float, object]:  # noqa: ANN003
    from tether.recurrent.planning.configuration import optimal_configuration

    t0 = cpu_clock()
    conf = optimal_configuration(*call, method, **kw)
    return cpu_clock() - t0, conf


@row("planning", "recurrent planning: APX (delta = 4) and the exact ILP (SCIP, HiGHS)")
def planning(quick: bool) -> dict:
    from tether import jit
    from tether.recurrent.planning.synthetic import exploration_instance

    seeds = range(2) if quick else range(6)
    per = []
    with jit.using(True):
        small = exploration_instance(0, n_vertices=70, n_edges=450, n_frontiers=12, n_robots=7)
        t0 = cpu_clock()
        for backend in ("scip", "highs"):
            _solve((small.graph, small.base, small.utilities, small.budget), "ilp", backend=backend)
        _solve((small.graph, small.base, small.utilities, small.budget), "apx", delta=4)
        warm = cpu_clock() - t0
        for seed in seeds:
            inst = exploration_instance(seed)
            call = (inst.graph, inst.base, inst.utilities, inst.budget)
            _solve(call, "apx", delta=4)
            apx = [_solve(call, "apx", delta=4) for _ in range(5)]
            rec = {
                "seed": seed,
                "vertices": inst.graph.number_of_nodes(),
                "edges": inst.graph.number_of_edges(),
                "frontiers": len(inst.utilities),
                "apx_s": statistics.median(t for t, _ in apx),
                "apx_utility": apx[0][1].utility,
            }
            for backend in ("scip", "highs"):
                took, conf = _solve(call, "ilp", backend=backend, time_limit_s=60.0)
                rec[f"{backend}_s"], rec[f"{backend}_utility"] = took, conf.utility
                rec[f"{backend}_proven"] = bool(conf.proven_optimal)
            rec["apx_gap"] = 1.0 - rec["apx_utility"] / rec["scip_utility"]
            per.append(rec)

    def med(key: str) -> float:
        return statistics.median(r[key] for r in per)

    def worst(key: str) -> float:
        return max(r[key] for r in per)

    lines = [
        Line(f"APX (delta = 4), {len(per)} instances of ~200 vertices (median)", "ms",
             1e3 * med("apx_s"), goal="<= 6 s (the paper)", goal_value=6e3,
             warmup_s=warm, extra={"max": 1e3 * worst("apx_s")}),
        Line("exact configuration ILP, SCIP, the same instances (median)", "s", med("scip_s"),
             goal="<= 0.5 s", goal_value=0.5, peer="the same ILP with HiGHS",
             peer_value=med("highs_s"), extra={"max": worst("scip_s"),
                                               "max_highs": worst("highs_s")}),
    ]  # fmt: skip
    return {"lines": lines, "details": {"instances": per}}


@register_table("planning")
def table_planning(doc: dict) -> str:
    out = [
        "| seed | vertices | edges | frontiers | APX (ms) | ILP SCIP (s) | ILP HiGHS (s) | "
        "proven optimal | APX utility gap |",
        "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- | ---: |",
    ]
    for r in doc["rows"].get("planning", {}).get("details", {}).get("instances", []):
        proven = "both" if r["scip_proven"] and r["highs_proven"] else "no"
        out.append(
            f"| {r['seed']} | {r['vertices']} | {r['edges']:,} | {r['frontiers']} | "
            f"{num(1e3 * r['apx_s'])} | {num(r['scip_s'])} | {num(r['highs_s'])} | {proven} | "
            f"{100 * r['apx_gap']:.1f} % |"
        )
    return "\n".join(out)


def run_process(scenario: str, sets: tuple[str, ...] = ()) -> tuple[float, float]:
    """``(wall, CPU)`` seconds of ``tether run SCENARIO --no-figures`` in a fresh process."""
    with tempfile.TemporaryDirectory() as tmp:
        argv = [*tether_cli(), "run", scenario, "--no-figures", "--out", str(Path(tmp) / "r")]
        for s in sets:
            argv += ["--set", s]
        return command(argv)


@row("recurrent_grass", "recurrent: a whole 900-step run on the Cluttered map", full_only=True)
def recurrent_grass(quick: bool) -> dict:
    if not (ROOT.parent / "shared" / "maps" / "grass.png").exists():
        raise FileNotFoundError("recurrent_grass reads ../shared/maps/grass.png")
    first = run_process("recurrent_grass")
    runs = [run_process("recurrent_grass") for _ in range(2)]
    cpu = statistics.median(c for _, c in runs)
    line = Line("recurrent_grass: 900 steps, 12 robots, whole process (CPU)", "s", cpu,
                goal="<= 10 s", goal_value=10.0, warmup_s=first[1],
                extra={"wall_s": statistics.median(w for w, _ in runs)})  # fmt: skip
    return {"lines": [line], "details": {"runs_cpu_s": [c for _, c in runs]}}
