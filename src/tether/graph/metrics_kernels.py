"""A small team's per-step graph metrics in one compiled call (numba).

:func:`tether.sim.team_metrics` records, every step, the components and lambda2 of the
true interaction graph, its shortest link and the robot pairs closer than the collision
distance. For a team of tens of robots each of these is a handful of numpy and scipy
calls whose overhead exceeds the arithmetic; :func:`team_metrics_kernel` computes all
four at once:

* components by union-find (:func:`~tether.graph.kernels.component_count_kernel`);
* lambda2 as :func:`tether.graph.fiedler.fiedler` gets it for up to 400 nodes: the second
  eigenvalue of ``numpy.linalg.eigh`` of the same dense Laplacian
  (:func:`~tether.graph.kernels.laplacian_dense_kernel`), here numba's ``eigh`` in the
  kernel (LAPACK ``dsyevd``, as numpy's: the same bits, tests compare them exactly;
  numpy's call overhead and argument checks are what it saves), clipped at 0, and
  exactly 0 when the graph is disconnected;
* the shortest link: ``sqrt`` of the smallest squared length of ``true_relative``'s
  rows summed in coordinate order, as ``numpy.linalg.norm(axis=1)`` sums them (so the
  same bits: ``sqrt`` is monotone and correctly rounded);
* close pairs: all pairs tested as :func:`~tether.graph.kernels.pairs_within_kernel`
  tests them, counted without storing them.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tether.graph.kernels import (
    component_count_kernel,
    laplacian_dense_kernel,
    pairs_within_kernel,
)


@njit(cache=True)
def team_metrics_kernel(n, pairs, positions, true_relative, collision_m, graph):  # noqa: ANN001, ANN201, PLR0913
    """``(components, lambda2, shortest link, close pairs)`` of one step.

    ``n`` graph nodes with ``(m, 2)`` int64 ``pairs``; ``positions`` the robots
    (``(n_robots, dim)``), ``true_relative`` the observation's ``(2m, dim)`` relative
    positions. ``graph=False`` skips components and lambda2 (returned as -1 and NaN: the
    caller has them). The shortest link is ``inf`` without links or with one node; close
    pairs are counted only for ``collision_m > 0``.
    """
    n_comp, lam = -1, np.nan
    if graph:
        n_comp = component_count_kernel(n, pairs) if n > 0 else 0
        lam = 0.0
        if n_comp == 1 and n >= 2:
            lap = laplacian_dense_kernel(n, pairs, np.ones(len(pairs)))
            lam = max(np.linalg.eigh(lap)[0][1], 0.0)
    shortest = np.inf
    if n > 1 and len(pairs) > 0:
        dim = true_relative.shape[1]
        low = np.inf
        for q in range(len(true_relative)):
            s = true_relative[q, 0] * true_relative[q, 0]
            for c in range(1, dim):
                s += true_relative[q, c] * true_relative[q, c]
            low = min(low, s)
        shortest = math.sqrt(low)
    close = 0
    if collision_m > 0:
        close = len(pairs_within_kernel(positions, collision_m))
    return n_comp, lam, shortest, close


def warm_up() -> None:
    """Compile (or load from numba's cache) the kernel for 2-D and 3-D teams."""
    pairs = np.array([[0, 1], [1, 2]], np.int64)
    for dim in (2, 3):
        pos = np.eye(3, dim)
        rel = np.ones((4, dim))
        for graph in (False, True):
            team_metrics_kernel(3, pairs, pos, rel, 1.0, graph)
