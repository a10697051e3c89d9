"""completeConfiguration, Step 20 of Algorithm 1 ("APX") of Banfi et al., Sec. IV-B.

After the subset search of :func:`tether.recurrent.planning.apx.solve_apx`, the robots
left over hang branches to the best frontiers still within reach.
"""

from __future__ import annotations

import numpy as np

from tether.recurrent.planning.problem import Problem
from tether.recurrent.planning.steiner import _path_edges

__all__ = ["complete_configuration"]


def complete_configuration(problem: Problem, tree: set[int]) -> set[int]:
    """Step 20: greedily hang branches to the best still-reachable frontiers.

    While robots remain, connect the unoccupied frontier of highest utility
    among those within the remaining budget (hops from the current tree) by
    a shortest path from its nearest tree vertex.
    """
    verts = set(tree)
    remaining = problem.budget - (len(verts) - 1)
    d = problem.dist
    while remaining > 0:
        members = np.fromiter(verts, dtype=np.intp)
        near = d[members]
        src = members[np.argmin(near, axis=0)]
        gap = near.min(axis=0)
        cand = [
            int(f) for f in problem.frontiers if f not in verts and gap[f] <= remaining
        ]  # frontiers are sorted by decreasing utility
        if not cand:
            break
        f = cand[0]
        for a, b in _path_edges(problem.pred, int(src[f]), f):
            verts.update((a, b))
        remaining = problem.budget - (len(verts) - 1)
    return verts
