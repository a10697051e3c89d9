"""The exact Steiner tree on SteinLib's instances: the published optimum, every time.

The instances of ``tests/data/steinlib`` (J. E. Beasley's set B, four of his set C and
C. Lin's ``lin01``; see the README there) are read with
:func:`tether.graph.steinlib.read_stp`. Instances with at most :data:`MAX_TERMINALS`
terminals are solved by
:func:`tether.recurrent.planning.steiner.steiner_tree` with the reference path and, if
numba is installed, with the compiled kernel; Dreyfus-Wagner's ``3^k`` work makes the
17-terminal ones take seconds even compiled (the benchmark suite's ``steiner_scaling``
row runs those). Every instance is also checked against networkx's 2-approximation, a
check of the reader and of the optimum table rather than of the solver.
"""

from __future__ import annotations

import re
from pathlib import Path

import networkx as nx
import pytest
from networkx.algorithms.approximation import steiner_tree as approximate_steiner_tree

from tether import jit
from tether.graph.steinlib import read_stp
from tether.recurrent.planning.steiner import steiner_tree

DATA = Path(__file__).parent / "data" / "steinlib"

#: name: (nodes, edges, terminals, optimum), from SteinLib's tables of sets B, C and LIN
B = {
    "b01": (50, 63, 9, 82),
    "b02": (50, 63, 13, 83),
    "b03": (50, 63, 25, 138),
    "b04": (50, 100, 9, 59),
    "b05": (50, 100, 13, 61),
    "b06": (50, 100, 25, 122),
    "b07": (75, 94, 13, 111),
    "b08": (75, 94, 19, 104),
    "b09": (75, 94, 38, 220),
    "b10": (75, 150, 13, 86),
    "b11": (75, 150, 19, 88),
    "b12": (75, 150, 38, 174),
    "b13": (100, 125, 17, 165),
    "b14": (100, 125, 25, 235),
    "b15": (100, 125, 50, 318),
    "b16": (100, 200, 17, 127),
    "b17": (100, 200, 25, 131),
    "b18": (100, 200, 50, 218),
    "c01": (500, 625, 5, 85),
    "c02": (500, 625, 10, 144),
    "c06": (500, 1000, 5, 55),
    "c07": (500, 1000, 10, 102),
    "lin01": (53, 80, 4, 503),
}

#: the exact solver runs on instances with at most this many terminals: b01, b02, b04,
#: b05, b07, b10, the C and LIN instances, a fraction of a second each; the next size,
#: 17 terminals, takes seconds compiled and more with the reference path (the
#: steiner_scaling row of python benchmarks/run.py)
MAX_TERMINALS = 13

SOLVED = [name for name, (_, _, k, _) in B.items() if k <= MAX_TERMINALS]
MODES = [False, True] if jit.available() else [False]


def test_every_instance_file_is_here_and_in_the_readme() -> None:
    assert sorted(p.stem for p in DATA.glob("*.stp")) == sorted(B)
    rows = re.findall(r"^\| ([a-z]+\d\d) \| (\d+) \| (\d+) \| (\d+) \| (\d+) \|$",
                      (DATA / "README.md").read_text(), flags=re.MULTILINE)  # fmt: skip
    assert {name: tuple(map(int, rest)) for name, *rest in rows} == B


@pytest.mark.parametrize("name", sorted(B))
def test_reader_and_the_2_approximation(name: str) -> None:
    """Sizes as published; networkx's Steiner 2-approximation within [OPT, 2 OPT]."""
    nodes, edges, k, optimum = B[name]
    graph, terminals = read_stp(DATA / f"{name}.stp")
    assert (graph.number_of_nodes(), graph.number_of_edges(), len(terminals)) == (nodes, edges, k)
    assert set(terminals) <= set(graph) and nx.is_connected(graph)
    for method in ("mehlhorn", "kou"):
        approx = approximate_steiner_tree(graph, terminals, weight="weight", method=method)
        cost = approx.size(weight="weight")
        assert optimum <= cost <= 2 * optimum, method


@pytest.mark.parametrize("kernel", MODES, ids=lambda on: "kernel" if on else "reference")
@pytest.mark.parametrize("name", SOLVED)
def test_exact_steiner_tree_meets_the_published_optimum(name: str, kernel: bool) -> None:
    *_, optimum = B[name]
    graph, terminals = read_stp(DATA / f"{name}.stp")
    with jit.using(kernel):
        cost, tree = steiner_tree(graph, terminals)
    assert cost == optimum
    assert nx.is_tree(tree)
    assert set(terminals) <= set(tree.nodes)
    assert all(graph.has_edge(u, v) for u, v in tree.edges)
    assert sum(graph.edges[e]["weight"] for e in tree.edges) == optimum
