"""The compiled max-flow of the ILP's cut separation finds the reference's cuts exactly.

:mod:`tether.recurrent.planning.ilp_kernels` against scipy's ``maximum_flow`` in
:meth:`DirectedCutModel._min_cut`: same flow value and the same two cuts
(both are unique for every maximum flow) on LP-like capacities of exploration graphs.
"""

from __future__ import annotations

import numpy as np
import pytest

from tether import jit
from tether.recurrent.planning import problem as _problem
from tether.recurrent.planning.ilp_model import SCALE, DirectedCutModel, reduce_dominated
from tether.recurrent.planning.synthetic import exploration_instance

pytestmark = pytest.mark.skipif(not jit.available(), reason="needs numba")


@pytest.mark.parametrize("seed", range(3))
def test_kernel_cuts_equal_reference(seed: int) -> None:
    inst = exploration_instance(
        seed, n_vertices=70, n_edges=450, n_frontiers=12, n_robots=7, n_busy=0
    )
    prob = _problem.build(inst.graph, inst.base, inst.utilities, inst.budget)
    dm = DirectedCutModel(prob, reduce_dominated(prob))
    rng = np.random.default_rng(seed)
    for trial in range(12):
        x = np.where(rng.random(dm.n_arcs) < 0.15, rng.random(dm.n_arcs), 0.0)
        if trial % 3 == 0:  # ties: many minimum cuts
            x = np.round(x * 4) / 4
        cap = np.round(x * SCALE).astype(np.int64)
        for t in range(1, dm.n):
            with jit.using(False):
                flow, inside, back = dm._min_cut(cap, t)
            with jit.using(True):
                k_flow, k_inside, k_back = dm._min_cut(cap, t)
                early, _, _ = dm._min_cut(cap, t, flow - 1e-4)
            assert k_flow == flow
            assert np.array_equal(k_inside, inside)
            assert np.array_equal(k_back, back)
            assert flow - 1e-4 <= early <= flow


def test_separation_equal_with_and_without_kernel() -> None:
    inst = exploration_instance(1, n_vertices=70, n_edges=450, n_frontiers=12, n_robots=7)
    prob = _problem.build(inst.graph, inst.base, inst.utilities, inst.budget)
    dm = DirectedCutModel(prob, reduce_dominated(prob))
    rng = np.random.default_rng(5)
    x = np.where(rng.random(dm.n_arcs) < 0.2, rng.random(dm.n_arcs), 0.0)
    y = rng.random(dm.n - 1)
    with jit.using(False):
        ref = dm.separate_fractional(x, y)
    with jit.using(True):
        got = dm.separate_fractional(x, y)
    assert len(ref) == len(got) > 0
    for (a, k), (b, j) in zip(ref, got, strict=True):
        assert k == j and np.array_equal(a, b)
