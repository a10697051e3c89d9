"""Dreyfus-Wagner Steiner trees against brute force on small random graphs.

Every test runs with the reference (numpy) path and, if numba is installed, with the
compiled kernel of :mod:`tether.recurrent.planning.steiner_kernels`; the
last test checks that both give the same optimum on larger graphs.
"""

from __future__ import annotations

import itertools

import networkx as nx
import numpy as np
import pytest

from tether import jit
from tether.recurrent.planning.steiner import steiner_tree

MODES = [False, True] if jit.available() else [False]


@pytest.fixture(autouse=True, params=MODES, ids=lambda on: "kernel" if on else "reference")
def kernel_mode(request: pytest.FixtureRequest):  # noqa: ANN201
    """Run each test with the compiled kernel off and on."""
    with jit.using(request.param):
        yield request.param


def brute_force_steiner(graph: nx.Graph, terminals: list, weight: str = "weight") -> float:
    """Cheapest connected vertex set holding the terminals, priced by its MST."""
    others = [v for v in graph if v not in set(terminals)]
    best = np.inf
    for r in range(len(others) + 1):
        for extra in itertools.combinations(others, r):
            sub = graph.subgraph([*terminals, *extra])
            if not nx.is_connected(sub):
                continue
            mst = nx.minimum_spanning_tree(sub, weight=weight)
            best = min(best, mst.size(weight=weight))
    return best


def random_weighted_graph(rng: np.random.Generator, n: int, p: float, integer: bool) -> nx.Graph:
    g = nx.gnp_random_graph(n, p, seed=int(rng.integers(1 << 30)))
    for u, v in g.edges:
        g.edges[u, v]["weight"] = (
            int(rng.integers(0, 6)) if integer else float(rng.uniform(0.0, 3.0))
        )
    return g


def assert_valid_tree(graph: nx.Graph, tree: nx.Graph, terminals: list, cost: float) -> None:
    assert set(terminals) <= set(tree.nodes)
    assert nx.is_tree(tree)
    for u, v in tree.edges:
        assert graph.has_edge(u, v)
    assert tree.size(weight="weight") == pytest.approx(cost, abs=1e-9)
    for v in tree:
        if v not in terminals:
            assert tree.degree(v) >= 2


@pytest.mark.parametrize("seed", range(60))
def test_matches_brute_force(seed: int) -> None:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(5, 11))
    g = random_weighted_graph(rng, n, float(rng.uniform(0.25, 0.7)), integer=seed % 2 == 0)
    comp = max(nx.connected_components(g), key=len)
    if len(comp) < 2:
        pytest.skip("degenerate random graph")
    k = int(rng.integers(2, min(len(comp), 6) + 1))
    terminals = [int(t) for t in rng.choice(sorted(comp), size=k, replace=False)]
    cost, tree = steiner_tree(g, terminals)
    assert cost == pytest.approx(brute_force_steiner(g, terminals), abs=1e-9)
    assert_valid_tree(g, tree, terminals, cost)


@pytest.mark.parametrize("seed", range(10))
def test_unit_weights_and_string_labels(seed: int) -> None:
    rng = np.random.default_rng(100 + seed)
    g0 = nx.connected_watts_strogatz_graph(11, 4, 0.3, seed=seed)
    g = nx.relabel_nodes(g0, {v: f"v{v}" for v in g0})  # no weight attribute: cost 1
    terminals = [f"v{t}" for t in rng.choice(11, size=4, replace=False)]
    cost, tree = steiner_tree(g, terminals)
    assert cost == brute_force_steiner(g, terminals)
    # With unit weights the cost is the number of edges = vertices - 1.
    assert tree.number_of_nodes() == cost + 1


def test_terminal_order_does_not_matter() -> None:
    rng = np.random.default_rng(7)
    g = random_weighted_graph(rng, 10, 0.5, integer=False)
    comp = sorted(max(nx.connected_components(g), key=len))
    terms = comp[:5]
    costs = {steiner_tree(g, list(perm)).cost for perm in itertools.permutations(terms)}
    assert max(costs) - min(costs) < 1e-9


def test_trivial_and_invalid_inputs() -> None:
    g = nx.path_graph(4)
    assert steiner_tree(g, []).cost == 0.0
    cost, tree = steiner_tree(g, [2, 2])
    assert cost == 0.0 and list(tree.nodes) == [2]
    assert steiner_tree(g, [0, 3]).cost == 3.0
    with pytest.raises(ValueError):
        steiner_tree(g, [0, 9])
    with pytest.raises(ValueError):
        steiner_tree(nx.DiGraph(g), [0, 1])
    g.add_node(9)
    with pytest.raises(nx.NetworkXNoPath):
        steiner_tree(g, [0, 9])
    h = nx.path_graph(3)
    h.edges[0, 1]["weight"] = -1.0
    with pytest.raises(ValueError):
        steiner_tree(h, [0, 2])


def test_too_many_terminals_are_refused_before_any_table_is_made() -> None:
    """Tables beyond MAX_TABLE_BYTES are refused with their size, on both paths."""
    g = nx.connected_watts_strogatz_graph(100, 4, 0.3, seed=1)
    with pytest.raises(ValueError, match=r"21 terminals on 100 vertices need 2\.3 GiB"):
        steiner_tree(g, range(21))
    cost, tree = steiner_tree(nx.star_graph(9), range(1, 10))
    assert cost == 9 and tree.number_of_edges() == 9


@pytest.mark.parametrize("seed", range(12))
def test_kernel_and_reference_agree(seed: int, kernel_mode: bool) -> None:
    """Same optimum on 30-120 vertices and up to 9 terminals: exactly with integer weights."""
    if not kernel_mode:
        pytest.skip("compares the kernel with the reference")
    rng = np.random.default_rng(1000 + seed)
    n = int(rng.integers(30, 121))
    g = nx.connected_watts_strogatz_graph(n, 4, 0.3, seed=seed)
    integer = seed % 2 == 0
    for u, v in g.edges:
        g.edges[u, v]["weight"] = int(rng.integers(0, 20)) if integer else float(rng.uniform(0, 5))
    terminals = [int(t) for t in rng.choice(n, size=int(rng.integers(2, 10)), replace=False)]
    fast, tree = steiner_tree(g, terminals)
    with jit.using(False):
        ref, _ = steiner_tree(g, terminals)
    if integer:
        assert fast == ref
    else:
        assert fast == pytest.approx(ref, rel=1e-12, abs=1e-12)
    assert_valid_tree(g, tree, terminals, fast)


@pytest.mark.parametrize("seed", range(6))
def test_edge_lists_follow_networkx_edge_order(seed: int) -> None:
    """The kernel's edge lists are the component's edges in networkx's edge-view order
    (the CSR, hence Dijkstra's ties and which optimal tree is returned, depend on it):
    a whole graph with self-loops and string labels, and one of two components."""
    from tether.recurrent.planning.steiner import _edge_lists

    rng = np.random.default_rng(seed)
    g = nx.connected_watts_strogatz_graph(40, 4, 0.3, seed=seed)
    g = nx.relabel_nodes(g, {v: f"n{(v * 7) % 40}" for v in g})  # adjacency order != labels
    for u, v in g.edges:
        g.edges[u, v]["weight"] = float(rng.integers(1, 9))
    g.add_edge("n3", "n3", weight=1.0)
    two = nx.disjoint_union(g, nx.cycle_graph(5))
    for graph, start in ((g, "n0"), (two, 0)):
        nodes = list(nx.node_connected_component(graph, start))
        index = {v: i for i, v in enumerate(nodes)}
        expected = [(index[u], index[v], w)
                    for u, v, w in graph.subgraph(nodes).edges(data="weight", default=1.0)
                    if u != v]  # fmt: skip
        us, vs, ws = _edge_lists(graph, nodes, index, "weight")
        assert list(zip(us, vs, ws, strict=True)) == expected


@pytest.mark.parametrize("seed", range(8))
def test_spanning_tree_shortcut_is_networkx_mst(seed: int) -> None:
    """``_spanning_tree`` gives networkx's Kruskal tree exactly (nodes, edges, their order
    and data) for trees with tied weights, for graphs with a cycle and for a forest."""
    from tether.recurrent.planning.steiner import _spanning_tree

    rng = np.random.default_rng(seed)
    tree = nx.random_labeled_tree(12, seed=seed)
    cyclic = tree.copy()
    cyclic.add_edge(0, 11)
    forest = nx.disjoint_union(tree, nx.path_graph(3))
    for g in (tree, cyclic, forest):
        for u, v in g.edges:
            g.edges[u, v]["weight"] = int(rng.integers(1, 4))  # ties
            g.edges[u, v]["id"] = (u, v)
        ours, theirs = _spanning_tree(g, "weight"), nx.minimum_spanning_tree(g, weight="weight")
        assert list(ours.nodes(data=True)) == list(theirs.nodes(data=True))
        assert list(ours.edges(data=True)) == list(theirs.edges(data=True))
        assert {v: list(ours.adj[v]) for v in ours} == {v: list(theirs.adj[v]) for v in theirs}
