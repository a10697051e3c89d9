"""Whether two trees' compiled Steiner kernels give the same arrays, bit for bit.

For a change to ``steiner_kernels.py`` that must not change results (a skip, a bound that
prunes only labels that fail anyway): loads the old tree's ``steiner_kernel`` from
``--old-src`` beside the installed one and runs both on the probe's 12 graphs
(``issue14_probes.steiner_graphs``) and ``--graphs`` random Watts-Strogatz graphs (10-120
vertices, 2-10 terminals, integer weights 0-4 with many ties on every other graph,
uniform weights on the rest). Compares the cost and the ``pred`` and ``split`` arrays
(hence the tree returned). Prints how many graphs differ in those arrays, in the cost
and in the tree's edges; exits 1 if any arrays differ.

    python benchmarks/check_steiner_kernels.py --old-src /tmp/old/src [--graphs 400]
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

os.environ.setdefault("TETHER_JIT", "on")

import networkx as nx  # noqa: E402
import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).parent))
from issue14_probes import steiner_graphs  # noqa: E402
from paired_steiner import _load  # noqa: E402
from tether.recurrent.planning import steiner_kernels as new  # noqa: E402


def csr(g: nx.Graph, terms: list) -> tuple:
    """The kernel's arguments for ``g`` (each edge in both rows, stable order)."""
    index = {v: i for i, v in enumerate(g)}
    us, vs, ws = [], [], []
    for u, v, w in g.edges(data="weight", default=1.0):
        us.append(index[u])
        vs.append(index[v])
        ws.append(w)
    w = np.array(ws, float)
    src = np.array(us + vs, np.int64)
    dst = np.array(vs + us, np.int64)
    order = np.argsort(src, kind="stable")
    indptr = np.zeros(len(index) + 1, np.int64)
    np.cumsum(np.bincount(src, minlength=len(index)), out=indptr[1:])
    term = np.array([index[t] for t in terms], np.int64)
    return indptr, dst[order], np.concatenate([w, w])[order], term


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--old-src", type=Path, required=True)
    ap.add_argument("--graphs", type=int, default=400)
    a = ap.parse_args()
    path = a.old_src / "tether" / "recurrent" / "planning" / "steiner_kernels.py"
    old = _load("old_steiner_kernels", path, path.read_text())
    cases = [(g, t) for _, _, _, g, t in steiner_graphs(0, 12)]
    rng = np.random.default_rng(11)
    for i in range(a.graphs):
        n = int(rng.choice([10, 30, 60, 120]))
        g = nx.connected_watts_strogatz_graph(n, 4, 0.3, seed=int(rng.integers(1 << 30)))
        for u, v in g.edges:
            g.edges[u, v]["weight"] = (
                float(rng.integers(0, 5)) if i % 2 else float(rng.uniform(0, 3))
            )
        k = min(int(rng.integers(2, 11)), n)
        cases.append((g, [int(x) for x in rng.choice(n, size=k, replace=False)]))
    differ = trees = costs = 0
    for g, terms in cases:
        args = csr(g, terms)
        (c0, p0, s0), (c1, p1, s1) = old.steiner_kernel(*args), new.steiner_kernel(*args)
        differ += not (c0 == c1 and np.array_equal(p0, p1) and np.array_equal(s0, s1))
        costs += c0 != c1
        full, root = (1 << (len(terms) - 1)) - 1, int(args[3][-1])
        e0 = {tuple(sorted(e)) for e in new.tree_edges(p0, s0, root, full).tolist()}
        e1 = {tuple(sorted(e)) for e in new.tree_edges(p1, s1, root, full).tolist()}
        trees += e0 != e1
    print(f"{len(cases)} graphs: {differ} with different cost, pred or split arrays; "
          f"{costs} with another cost; {trees} with another tree")  # fmt: skip
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
