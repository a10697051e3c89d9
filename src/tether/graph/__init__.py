"""The graph layer: links, Laplacians, lambda2 and the Fiedler vector, components.

A graph on ``n`` nodes is an ``(m, 2)`` integer array of undirected links
``pairs`` (``i < j``) with optional ``(m,)`` non-negative weights. Everything
here is plain arrays and sparse matrices, so that 10,000-robot teams stay cheap.

* :mod:`tether.graph.structure` -- neighbour pairs (k-d tree), adjacency,
  Laplacians, connected components, stretch;
* :mod:`tether.graph.fiedler` -- lambda2 and the Fiedler vector, one public
  function with ``method=`` dispatch (dense, subset, sparse, warm, small);
* :mod:`tether.graph.warm` -- the certified warm-started solver for large teams,
  on :mod:`tether.graph.links` (a Laplacian kept as its links);
* :mod:`tether.graph.small` -- the certified warm-started dense solver for teams of
  17-400 robots (compiled in :mod:`tether.graph.small_kernels`, same bits);
* :mod:`tether.graph.steinlib` -- a strict reader of SteinLib's STP files (Steiner
  problems in graphs, as ``networkx`` graphs; not imported here).
"""

from tether.graph.fiedler import DENSE_MAX_N, SUBSET_MAX_N, algebraic_connectivity, fiedler
from tether.graph.structure import (
    adjacency,
    component_count,
    components,
    expand_rows,
    is_connected,
    laplacian,
    laplacian_dense,
    pairs_within,
    stretch,
)
from tether.graph.warm import WarmState, warm_fiedler

__all__ = [
    "DENSE_MAX_N",
    "SUBSET_MAX_N",
    "WarmState",
    "adjacency",
    "algebraic_connectivity",
    "component_count",
    "components",
    "expand_rows",
    "fiedler",
    "is_connected",
    "laplacian",
    "laplacian_dense",
    "pairs_within",
    "stretch",
    "warm_fiedler",
]
