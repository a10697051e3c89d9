"""The exact Steiner tree against networkx's approximation, warm and cold.

Peer: ``networkx.algorithms.approximation.steiner_tree(method="mehlhorn")`` (a
2-approximation in Python), on the same graph and terminals, in the same process.

* ``steiner_random``: 12 random connected graphs (Watts-Strogatz, 50-500 vertices,
  3-10 terminals, integer weights 1-99), kernels on, after a warm-up call per graph;
  the two solvers in turns, medians; the row is the median over graphs of the ratio.
* ``steiner_steinlib``: the public SteinLib instances with at most 10 terminals that the
  repository holds (``tests/data/steinlib``; cost checked against the published
  optimum). *Warm*: as above. *Cold*: each instance in :data:`COLD_RUNS` fresh
  processes with the default ``TETHER_JIT`` (``auto``), the first call of each solver
  timed (ours first), as a short ``tether`` command or a first plan pays it; medians.
"""

from __future__ import annotations

import json
import re
import statistics
from pathlib import Path

import networkx as nx
import numpy as np

from suite.core import ROOT, Line, cpu_clock, fresh_process, row

STEINLIB = ROOT / "tests" / "data" / "steinlib"
MAX_TERMINALS = 10
COLD_RUNS = 3
"""Fresh processes per instance for the cold figures (medians; one with ``--quick``)."""


def random_graphs(seed: int, count: int) -> list[tuple[int, nx.Graph, list[int]]]:
    """``(index, graph, terminals)``: connected Watts-Strogatz graphs, 50-500 vertices,
    3-10 terminals, integer weights 1-99."""
    rng = np.random.default_rng(seed)
    out = []
    for i in range(count):
        n = int(rng.choice([50, 100, 200, 500]))
        k = int(rng.integers(3, 11))
        g = nx.connected_watts_strogatz_graph(n, 6, 0.3, seed=int(rng.integers(1 << 30)))
        for u, v in g.edges:
            g.edges[u, v]["weight"] = float(rng.integers(1, 100))
        out.append((i, g, [int(t) for t in rng.choice(n, size=k, replace=False)]))
    return out


def optima() -> dict[str, int]:
    """Instance name -> published optimum, from the table of the data folder's README."""
    text = (STEINLIB / "README.md").read_text()
    rows = re.findall(r"^\| ([a-z]+\d\d) \| \d+ \| \d+ \| \d+ \| (\d+) \|$", text, re.MULTILINE)
    return {name: int(opt) for name, opt in rows}


def instances() -> list[Path]:
    """The SteinLib files with at most :data:`MAX_TERMINALS` terminals."""
    out = []
    for path in sorted(STEINLIB.glob("*.stp")):
        found = re.search(r"^Terminals\s+(\d+)", path.read_text(), re.MULTILINE)
        if found and int(found.group(1)) <= MAX_TERMINALS:
            out.append(path)
    return out


def _warm_pair(graph: nx.Graph, terminals: list, rounds: int) -> dict:
    """Warm-up call of each, then both in turns: medians, costs."""
    from networkx.algorithms.approximation import steiner_tree as mehlhorn

    from tether.recurrent.planning.steiner import steiner_tree

    t0 = cpu_clock()
    cost, _ = steiner_tree(graph, terminals)
    warm = cpu_clock() - t0
    approx = mehlhorn(graph, terminals, method="mehlhorn")
    ours, peer = [], []
    for _ in range(rounds):
        t0 = cpu_clock()
        steiner_tree(graph, terminals)
        ours.append(cpu_clock() - t0)
        t0 = cpu_clock()
        mehlhorn(graph, terminals, method="mehlhorn")
        peer.append(cpu_clock() - t0)
    exact_s, peer_s = statistics.median(ours), statistics.median(peer)
    return {
        "vertices": graph.number_of_nodes(),
        "edges": graph.number_of_edges(),
        "terminals": len(terminals),
        "cost": cost,
        "mehlhorn_cost": float(approx.size(weight="weight")),
        "warmup_s": warm,
        "exact_s": exact_s,
        "mehlhorn_s": peer_s,
        "ratio": exact_s / peer_s,
    }


def _summary(per: list[dict], key: str = "ratio") -> tuple[float, float]:
    ratios = [p[key] for p in per]
    return statistics.median(ratios), max(ratios)


@row("steiner_random", "exact Steiner tree against networkx's approximation, random graphs")
def steiner_random(quick: bool) -> dict:
    from tether import jit

    graphs = random_graphs(0, 12)[: 3 if quick else 12]
    with jit.using(True):
        per = [{"graph": i, **_warm_pair(g, t, 2 if quick else 7)} for i, g, t in graphs]
    median, worst = _summary(per)
    line = Line(
        f"exact Steiner tree / networkx mehlhorn, {len(per)} random graphs, warm (median ratio)",
        "x",
        median,
        goal="<= 1x",
        goal_value=1.0,
        peer="networkx mehlhorn (same graphs, in turns)",
        warmup_s=per[0]["warmup_s"],
        extra={"worst_ratio": worst},
    )
    return {"lines": [line], "details": {"graphs": per}}


COLD = """
import json, time
from pathlib import Path
from networkx.algorithms.approximation import steiner_tree as mehlhorn
from tether.graph.steinlib import read_stp
from tether.recurrent.planning.steiner import steiner_tree
from tether import jit
inst = read_stp(Path({path!r}))
g, t = inst.graph, list(inst.terminals)
t0 = time.process_time(); cost, _ = steiner_tree(g, t); exact = time.process_time() - t0
t0 = time.process_time(); mehlhorn(g, t, method="mehlhorn"); peer = time.process_time() - t0
print(json.dumps({{"cost": cost, "exact_s": exact, "mehlhorn_s": peer,
                  "compiled": bool(jit.enabled())}}))
"""


@row("steiner_steinlib", "exact Steiner tree against networkx's approximation, SteinLib")
def steiner_steinlib(quick: bool) -> dict:
    from tether import jit
    from tether.graph.steinlib import read_stp

    best = optima()
    paths = instances()
    per = []
    with jit.using(True):
        for path in paths:
            inst = read_stp(path)
            rec = {"instance": path.stem, "optimum": best.get(path.stem)}
            rec.update(_warm_pair(inst.graph, list(inst.terminals), 3 if quick else 15))
            per.append(rec)
    for rec, path in zip(per, paths, strict=True):
        runs = [fresh_process(COLD.format(path=str(path)), env={"TETHER_JIT": ""})[0]
                for _ in range(1 if quick else COLD_RUNS)]  # fmt: skip
        rec["cold_exact_s"] = statistics.median(r["exact_s"] for r in runs)
        rec["cold_mehlhorn_s"] = statistics.median(r["mehlhorn_s"] for r in runs)
        rec["cold_ratio"] = statistics.median(r["exact_s"] / r["mehlhorn_s"] for r in runs)
        rec["cold_compiled"] = any(r["compiled"] for r in runs)
        rec["cold_cost"] = max(r["cost"] for r in runs)
    bad = [r["instance"] for r in per if not r["cost"] == r["cold_cost"] == r["optimum"]]
    if bad:
        raise AssertionError(f"steiner_tree missed the published optimum on {bad}")
    names = ", ".join(r["instance"] for r in per)
    warm_median, warm_worst = _summary(per)
    cold_median, cold_worst = _summary(per, "cold_ratio")
    peer = "networkx mehlhorn (same instances, same process)"
    lines = [
        Line(
            f"exact Steiner tree / mehlhorn, SteinLib <= {MAX_TERMINALS} terminals ({names}), "
            "warm (median ratio)",
            "x",
            warm_median,
            goal="<= 1x",
            goal_value=1.0,
            peer=peer,
            warmup_s=per[0]["warmup_s"],
            extra={"worst_ratio": warm_worst},
        ),
        Line(
            f"the same, cold: first call in a fresh process (median of {COLD_RUNS}), "
            "TETHER_JIT=auto (median ratio)",
            "x",
            cold_median,
            goal="<= 1x",
            goal_value=1.0,
            peer=peer,
            extra={"worst_ratio": cold_worst},
        ),
    ]
    return {"lines": lines, "details": {"instances": per}}


@row(
    "steiner_scaling",
    "exact Steiner tree against the number of terminals (SteinLib B)",
    full_only=True,
)
def steiner_scaling(quick: bool) -> dict:
    """Every set-B instance with 9-19 terminals, compiled (and the reference up to 13):
    one solve each after the warm-up of the row above, cost against the optimum."""
    from tether import jit
    from tether.graph.steinlib import read_stp
    from tether.recurrent.planning.steiner import steiner_tree

    best = optima()
    per = []
    paths = sorted(STEINLIB.glob("b*.stp"))
    loaded = [(p.stem, read_stp(p)) for p in paths]
    loaded = sorted((x for x in loaded if len(x[1].terminals) <= 19),
                    key=lambda x: (len(x[1].terminals), x[0]))  # fmt: skip
    with jit.using(True):
        steiner_tree(loaded[0][1].graph, list(loaded[0][1].terminals))
    for name, inst in loaded:
        g, t = inst.graph, list(inst.terminals)
        rec = {"instance": name, "vertices": g.number_of_nodes(), "edges": g.number_of_edges(),
               "terminals": len(t), "optimum": best[name]}  # fmt: skip
        with jit.using(True):
            t0 = cpu_clock()
            rec["cost"], _ = steiner_tree(g, t)
            rec["compiled_s"] = cpu_clock() - t0
        rec["reference_s"] = None
        if len(t) <= 13:
            with jit.using(False):
                t0 = cpu_clock()
                steiner_tree(g, t)
                rec["reference_s"] = cpu_clock() - t0
        if rec["cost"] != rec["optimum"]:
            raise AssertionError(f"{name}: cost {rec['cost']} against the optimum {rec['optimum']}")
        per.append(rec)
    by_k: dict[int, list[float]] = {}
    for r in per:
        by_k.setdefault(r["terminals"], []).append(r["compiled_s"])
    lines = [Line(f"exact Steiner tree, SteinLib B, {k} terminals (median of {len(v)})", "s",
                  statistics.median(v)) for k, v in sorted(by_k.items())]  # fmt: skip
    return {"lines": lines, "details": {"instances": per}}


if __name__ == "__main__":  # a quick look: python -m suite.steiner (from benchmarks/)
    print(json.dumps(steiner_steinlib(True)["details"], indent=1, default=str))
