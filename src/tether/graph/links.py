"""A weighted graph's Laplacian kept as its list of links, for large teams.

What the warm Fiedler solver (:mod:`tether.graph.warm`) needs of ``L = sum_k w_k
(e_i - e_j)(e_i - e_j)'`` without building a scipy matrix each step: the product
``L x`` in ``O(m)``, the shifted matrix ``L - tau I`` for a sparse factorization, and
a bound on ``||L_b - L_a||_2`` between two graphs on the same nodes (with Weyl's
inequality, ``|lambda_k(L_b) - lambda_k(L_a)| <= ||L_b - L_a||_2``, it carries a
certified eigenvalue bound from one graph to the next; Horn and Johnson, *Matrix
Analysis*, Cor. 4.3.15). With :func:`tether.jit.enabled`, the kernels of
:mod:`tether.graph.link_kernels` do the same arithmetic in the same order.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.sparse as sp

from tether import jit


@dataclass(frozen=True)
class Links:
    """A graph's links in canonical form: ``lo < hi``, sorted by ``key = lo n + hi``, unique.

    Self-loops and links of weight ``<= 0`` are dropped (they add nothing to ``L``);
    repeated links are merged, their weights summed.
    """

    n: int
    lo: np.ndarray
    hi: np.ndarray
    w: np.ndarray
    keys: np.ndarray

    @classmethod
    def from_pairs(cls, n: int, pairs: np.ndarray, weights: np.ndarray | None = None) -> Links:
        """The canonical links of ``(m, 2)`` ``pairs`` with optional ``(m,)`` weights."""
        pairs = np.asarray(pairs, dtype=np.int64).reshape(-1, 2)
        w = np.ones(len(pairs)) if weights is None else np.asarray(weights, dtype=float)
        if jit.enabled():
            from tether.graph.link_kernels import canonical_kernel

            ok, lo, hi, wk, keys, deg = canonical_kernel(n, np.ascontiguousarray(pairs), w)
            if ok:
                links = cls(n, lo, hi, wk, keys)
                links.__dict__["degrees"] = deg  # the cached property, computed alike
                return links
        lo = np.minimum(pairs[:, 0], pairs[:, 1])
        hi = np.maximum(pairs[:, 0], pairs[:, 1])
        keep = (lo != hi) & (w > 0)
        if not keep.all():
            lo, hi, w = lo[keep], hi[keep], w[keep]
        keys = lo * n + hi
        if len(keys) > 1 and not bool(np.all(keys[1:] > keys[:-1])):
            order = np.argsort(keys, kind="stable")
            keys, first = np.unique(keys[order], return_index=True)
            w = np.add.reduceat(w[order], first)
            lo, hi = keys // n, keys % n
        return cls(n, lo, hi, w, keys)

    @cached_property
    def degrees(self) -> np.ndarray:
        """``(n,)`` weighted degrees."""
        return np.bincount(self.lo, self.w, self.n) + np.bincount(self.hi, self.w, self.n)

    def product(self, x: np.ndarray) -> np.ndarray:
        """``L x`` (``(n,)``)."""
        x = np.asarray(x, dtype=float)
        if jit.enabled():
            from tether.graph.link_kernels import product_kernel

            return product_kernel(self.n, self.lo, self.hi, self.w, x)
        d = self.w * (x[self.lo] - x[self.hi])
        return np.bincount(self.lo, d, self.n) - np.bincount(self.hi, d, self.n)

    def shifted(self, tau: float) -> sp.csc_matrix:
        """``L - tau I`` as a CSC matrix with sorted row indices."""
        n = self.n
        if jit.enabled():
            from tether.graph.link_kernels import shifted_csc_kernel

            indptr, indices, data = shifted_csc_kernel(n, self.lo, self.hi, self.w, float(tau))
        else:
            deg = self.degrees
            nodes = np.arange(n, dtype=np.int64)
            cols = np.concatenate([self.hi, self.lo, nodes])
            rows = np.concatenate([self.lo, self.hi, nodes])
            data = np.concatenate([-self.w, -self.w, deg - float(tau)])
            order = np.lexsort((rows, cols))
            indices, data = rows[order], data[order]
            indptr = np.zeros(n + 1, dtype=np.int64)
            np.cumsum(np.bincount(cols, minlength=n), out=indptr[1:])
        return sp.csc_matrix((data, indices, indptr), shape=(n, n))

    @property
    def max_degree(self) -> float:
        """The largest weighted degree (``||L||_2 <= 2`` times it)."""
        return float(self.degrees.max()) if self.n else 0.0


def change_bound(a: Links, b: Links) -> float:
    """An upper bound on ``||L_b - L_a||_2``: ``2 max_i sum_j |w_b(ij) - w_a(ij)|``.

    ``L_b - L_a`` is the Laplacian of the signed weight changes; a symmetric matrix's
    2-norm is at most its largest absolute row sum (Gershgorin), here at most twice
    the node's summed absolute changes. A link present in one graph only changes by
    its whole weight.
    """
    if a.n != b.n:
        raise ValueError(f"graphs on {a.n} and {b.n} nodes")
    n = a.n
    if jit.enabled():
        from tether.graph.link_kernels import change_kernel

        acc = change_kernel(n, a.keys, a.lo, a.hi, a.w, b.keys, b.lo, b.hi, b.w)
    else:
        keys = np.union1d(a.keys, b.keys)
        wa = _on(keys, a)
        wb = _on(keys, b)
        d = np.abs(wb - wa)
        acc = np.bincount(keys // n, d, n) + np.bincount(keys % n, d, n)
    return 2.0 * float(acc.max()) if n else 0.0


def _on(keys: np.ndarray, g: Links) -> np.ndarray:
    """``g``'s weights on the sorted ``keys`` (a superset of its own), 0 where absent."""
    out = np.zeros(len(keys))
    if len(g.keys):
        out[np.searchsorted(keys, g.keys)] = g.w
    return out
