"""The reward terms of one step and the reward they make: ``sum(weight * term)``.

Every term is a team quantity (:data:`tether.envs.options.TERMS` says what one unit is);
every agent gets the team's reward, and every term is reported in each agent's ``info``
(``info["terms"]``), so that a policy can be scored on any of them afterwards. Connectivity
is measured, never enforced: an action that breaks a link is carried out, and the terms
say so.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components, minimum_spanning_tree

from tether.sensing import Observation
from tether.sim import StepRecord


def bottleneck_margin(
    n_nodes: int, pairs: np.ndarray, lengths_m: np.ndarray, range_m: float
) -> float:
    """``1 - L / range_m`` with ``L`` the longest link of a shortest spanning tree (the
    smallest length such that the links no longer than it connect every node); 0 when
    the graph is disconnected, 1 for a single node."""
    if n_nodes <= 1:
        return 1.0
    if len(pairs) < n_nodes - 1:
        return 0.0
    w = np.maximum(lengths_m, 1e-12)  # a zero weight would be a missing link to scipy
    graph = coo_matrix((w, (pairs[:, 0], pairs[:, 1])), shape=(n_nodes, n_nodes))
    tree = minimum_spanning_tree(graph)
    if tree.nnz < n_nodes - 1:
        return 0.0
    return float(max(1.0 - tree.data.max() / range_m, 0.0))


def base_fraction(n: int, n_nodes: int, pairs: np.ndarray) -> float:
    """Fraction of the ``n`` robots in a component with a fixed node (nodes ``n..``)."""
    if n_nodes <= n:
        return 0.0
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n_nodes, n_nodes))
    _, label = connected_components(graph, directed=False)
    return float(np.isin(label[:n], label[n:]).mean())


def step_terms(
    rec: StepRecord,
    obs: Observation,
    nodes: np.ndarray,
    n: int,
    range_m: float,
    *,
    progress: float,
    targets: int,
    blocked: int,
    clearance: int,
) -> dict[str, float]:
    """Every term of :data:`~tether.envs.options.TERMS` for one step (``nodes``: the
    positions of the robots, then of the fixed nodes)."""
    pairs = np.asarray(obs.pairs, dtype=np.int64).reshape(-1, 2)
    lengths = np.linalg.norm(nodes[pairs[:, 0]] - nodes[pairs[:, 1]], axis=1)
    lam = float(rec.lambda2) if np.isfinite(rec.lambda2) else 0.0
    return {
        "progress": float(progress),
        "targets": float(targets),
        "connected": float(rec.connected),
        "disconnected": float(not rec.connected),
        "lambda2": lam,
        "margin": bottleneck_margin(len(nodes), pairs, lengths, range_m),
        "base": base_fraction(n, len(nodes), pairs),
        "collisions": float(rec.collisions),
        "blocked": float(blocked),
        "clearance": float(clearance),
    }


def reward(terms: dict[str, float], weights: dict[str, float]) -> float:
    """``sum(weight * term)`` over the terms."""
    return float(sum(weights[name] * value for name, value in terms.items()))
