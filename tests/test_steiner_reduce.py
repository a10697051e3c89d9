"""The exact reductions before the Steiner dynamic programme (``steiner_reduce``).

Each degree test is shown to fire on a graph made for it (what goes, what is fixed, what
an edge stands for), and on random graphs the reduced problem's optimum plus the fixed
edges equals the optimum of the unreduced one, both by the plain Dreyfus-Wagner
programme (:func:`tether.recurrent.planning.steiner.dreyfus_wagner`, which reduces
nothing), and the expanded tree is a tree of the input of that cost.
"""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest

from tether.recurrent.planning.steiner import all_pairs, dreyfus_wagner, sparse_dreyfus_wagner
from tether.recurrent.planning.steiner_reduce import reduce_instance


def _k4(weights: dict[tuple[int, int], float]) -> tuple[list[int], list[int], list[float]]:
    """Edge lists of the complete graph on 0..3 (weight 10 unless given), then extras."""
    edges = {(u, v): 10.0 for u in range(4) for v in range(u + 1, 4)}
    edges.update(weights)
    us, vs, ws = zip(*((u, v, w) for (u, v), w in edges.items()), strict=True)
    return list(us), list(vs), list(ws)


def _reduced_edges(red) -> dict[frozenset, tuple[float, tuple[int, ...]]]:  # noqa: ANN001
    return {frozenset((a, b)): (w, p)
            for a, b, w, p in zip(red.us.tolist(), red.vs.tolist(), red.ws.tolist(), red.paths,
                                  strict=True)}  # fmt: skip


def test_non_terminal_of_degree_one_goes() -> None:
    # a path 3-4-5 hangs from the K4; the terminals' cheapest edges lead to non-terminals
    us, vs, ws = _k4({(3, 4): 1.0, (4, 5): 1.0, (0, 2): 5.0, (1, 3): 5.0})
    red = reduce_instance(6, us, vs, ws, [0, 1])
    assert red.size == 4 and len(red.us) == 6 and red.fixed == [] and red.fixed_cost == 0


@pytest.mark.parametrize(("direct", "kept"), [(None, 5.0), (6.0, 5.0), (4.0, 4.0)])
def test_non_terminal_of_degree_two_becomes_one_edge(direct: float | None, kept: float) -> None:
    """0-4-1 (2 + 3) becomes an edge 0-1 of 5 standing for both input edges; an edge
    0-1 there already stays when it is not heavier."""
    extra = {(0, 4): 2.0, (4, 1): 3.0, (0, 3): 12.0, (1, 3): 9.0}
    if direct is not None:
        extra[0, 1] = direct
    us, vs, ws = _k4(extra)
    red = reduce_instance(5, us, vs, ws, [0, 3])
    assert red.size == 4 and red.fixed == []
    w, path = _reduced_edges(red)[frozenset((0, 1))]
    assert w == kept
    names = sorted((us[i], vs[i]) for i in path)
    assert names == ([(0, 1)] if kept == direct else [(0, 4), (4, 1)])


def test_terminal_of_degree_one_is_fixed_to_its_neighbour() -> None:
    us, vs, ws = _k4({(2, 4): 7.0, (0, 2): 12.0})  # terminal 4 hangs from 2
    red = reduce_instance(5, us, vs, ws, [4, 0])
    assert red.fixed_cost == 7.0 and [(us[i], vs[i]) for i in red.fixed] == [(2, 4)]
    assert red.size == 4 and sorted(red.terminals) == [0, 2]


def test_nearest_terminal_merges_two_terminals() -> None:
    """0 and 1 are each other's cheapest neighbour: their edge is fixed, one terminal
    fewer; 2's cheapest edge (to the non-terminal 3) is left alone."""
    extra = {(0, 1): 1.0, (2, 3): 1.0, (0, 2): 11.0, (1, 2): 12.0}
    us, vs, ws = _k4({**extra, (0, 4): 10.0, (2, 4): 10.0, (3, 4): 10.0})
    red = reduce_instance(5, us, vs, ws, [0, 1, 2])
    assert red.fixed_cost == 1.0 and [(us[i], vs[i]) for i in red.fixed] == [(0, 1)]
    assert len(red.terminals) == 2 and red.size == 4
    # the merged terminal keeps the cheaper of its two edges to each other vertex
    assert sorted(red.ws.tolist()) == [1.0, 10.0, 10.0, 10.0, 10.0, 11.0]


def test_zero_weight_edge_merges_its_ends() -> None:
    """K4 plus a vertex 4 tied to 3 at no cost and to 0, 1 and 2: 3 and 4 become one
    vertex, whose edge to each other vertex is the cheaper of the two."""
    us, vs, ws = _k4({(0, 2): 5.0, (1, 3): 5.0, (3, 4): 0.0, (0, 4): 7.0, (1, 4): 11.0,
                      (2, 4): 12.0})  # fmt: skip
    red = reduce_instance(5, us, vs, ws, [0, 1])
    assert red.size == 4 and red.fixed_cost == 0.0
    assert [(us[i], vs[i]) for i in red.fixed] == [(3, 4)]
    assert sorted(red.ws.tolist()) == [5.0, 5.0, 7.0, 10.0, 10.0, 10.0]
    assert min(red.ws) > 0


def test_one_terminal_left_means_nothing_else() -> None:
    red = reduce_instance(3, [0, 1], [1, 2], [2.0, 3.0], [0, 2])
    assert red.fixed_cost == 5.0 and red.size == 1 and len(red.us) == 0
    assert len(red.terminals) == 1


def _plain_optimum(n: int, us, vs, ws, terminals) -> float:  # noqa: ANN001
    dist, pred = all_pairs(n, us, vs, ws)
    return dreyfus_wagner(dist, pred, terminals)[0]


@pytest.mark.parametrize("seed", range(80))
def test_reduced_optimum_plus_fixed_edges_is_the_optimum(seed: int) -> None:
    """Random sparse graphs (trees with a few chords: many low degrees, so every test
    fires), integer weights with zeros or positive floats, 2-7 terminals."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(6, 30))
    g = nx.random_labeled_tree(n, seed=seed)
    for _ in range(int(rng.integers(0, n))):
        u, v = (int(x) for x in rng.choice(n, size=2, replace=False))
        g.add_edge(u, v)
    us, vs = (list(x) for x in zip(*g.edges, strict=True))
    if seed % 2:
        ws = [float(rng.integers(0, 6)) for _ in us]
    else:
        ws = [float(rng.uniform(0.1, 3.0)) for _ in us]
    terminals = [int(t) for t in rng.choice(n, size=int(rng.integers(2, min(n, 7) + 1)),
                                            replace=False)]  # fmt: skip
    red = reduce_instance(n, us, vs, ws, terminals)
    rest, pairs = 0.0, []
    if len(red.terminals) > 1:
        dist, pred = all_pairs(red.size, red.us, red.vs, red.ws)
        rest, pairs = dreyfus_wagner(dist, pred, red.terminals)
    optimum = _plain_optimum(n, us, vs, ws, terminals)
    assert red.fixed_cost + rest == pytest.approx(optimum, abs=1e-9)
    # the expanded edges: a subgraph of the input joining the terminals, of the same cost
    # (a merged zero-weight edge may lie apart from them)
    edge_of = {frozenset((a, b)): i for i, (a, b) in enumerate(zip(red.us, red.vs, strict=True))}
    chosen = set(red.fixed)
    for a, b in pairs:
        chosen.update(red.paths[edge_of[frozenset((a, b))]])
    sub = nx.Graph()
    sub.add_nodes_from(terminals)
    sub.add_weighted_edges_from((us[i], vs[i], ws[i]) for i in chosen)
    assert set(terminals) <= nx.node_connected_component(sub, terminals[0])
    assert sub.size(weight="weight") == pytest.approx(optimum, abs=1e-9)


@pytest.mark.parametrize("seed", range(30))
def test_sparse_programme_matches_the_dense_one(seed: int) -> None:
    """``sparse_dreyfus_wagner`` (edge rounds, no distance table; the reference path on
    reduced graphs) finds the dense programme's optimum, with a tree of that cost."""
    rng = np.random.default_rng(500 + seed)
    n = int(rng.integers(8, 40))
    g = nx.connected_watts_strogatz_graph(n, 4, 0.4, seed=seed)
    us, vs = (np.array(x, dtype=np.int64) for x in zip(*g.edges, strict=True))
    ws = (
        rng.integers(1, 9, size=len(us)).astype(float) if seed % 2 else rng.uniform(0.1, 4, len(us))
    )
    terminals = [int(t) for t in rng.choice(n, size=int(rng.integers(2, 8)), replace=False)]
    cost, pairs = sparse_dreyfus_wagner(n, us, vs, ws, terminals)
    assert cost == pytest.approx(_plain_optimum(n, us, vs, ws, terminals), abs=1e-9)
    weight = {frozenset((int(a), int(b))): w for a, b, w in zip(us, vs, ws, strict=True)}
    tree = nx.Graph()
    tree.add_nodes_from(terminals)
    tree.add_weighted_edges_from((a, b, weight[frozenset((a, b))]) for a, b in pairs)
    assert set(terminals) <= nx.node_connected_component(tree, terminals[0])
    assert tree.size(weight="weight") == pytest.approx(cost, abs=1e-9)
