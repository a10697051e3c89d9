"""The weighted graph ``G_lambda`` of the team (App. A, steps 1-2).

Continuous-connectivity paper (Nestmeyer et al., "Decentralized simultaneous
multi-target exploration using a connected network of multiple robots"),
Sec. 2 and Appendix A, after Robuffo Giordano et al. (2013).

Weights
-------
For robots ``i != j`` with distance ``d_ij`` and line-of-sight clearance
``d_ijo = min_{s in [0,1], o in O} ||q_i + s (q_j - q_i) - o||``::

    W_ij = A(d_ij) * B(d_ijo) * C_i * C_j                       (App. A, step 2)
    A(d)   = 1 - S(d; R's, Rs)      range factor, 0 iff d >= Rs          (a)
    B(d)   = S(d; Ro, R'o)          obstacle factor, 0 iff d_ijo <= Ro   (b)
    C_i    = prod_{k != i} G(d_ik)  collision factor of robot i          (c)
    G(d)   = S(d; Rc, R'c)          0 iff d <= Rc

so ``W_ij = 0`` exactly when (a) the pair is out of range, (b) its line of
sight comes within ``Ro`` of an obstacle point, or (c) some robot ``k`` is
within ``Rc`` of ``i`` or of ``j``. ``P_ij = A B`` is the *pair factor*.

The smooth step ``S`` and its log-derivative are in
:mod:`tether.continuous.connectivity.potential`; line-of-sight clearance ``d_ijo`` comes
from the world layer's :class:`tether.world.clearance.ObstacleIndex`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cache

import numpy as np

from tether import floats, jit
from tether.continuous.connectivity.params import ConnectivityParams
from tether.continuous.connectivity.potential import smooth_step, smooth_step_log_derivative
from tether.graph import SUBSET_MAX_N, fiedler, laplacian_dense, pairs_within, small
from tether.graph.fiedler import Method, _syevr_lwork
from tether.graph.warm import WarmState
from tether.world.clearance import ObstacleIndex, einsum_order


@dataclass(slots=True)
class WeightedGraph:
    """Weights of App. A with everything the gradient needs (arrays over pairs).

    ``pairs`` are the ``(m, 2)`` robot pairs within ``Rs`` (``i < j``);
    ``coll_pairs`` the ``(mc, 2)`` pairs within ``R'c``. Per pair:
    ``dP_di``/``dP_dj`` are ``(m, dim)`` derivatives of the pair factor with
    respect to ``q_i``/``q_j``, ``clearance_m`` the line-of-sight clearance
    (``inf`` if beyond ``R'o``). Per collision pair: ``coll_unit`` is
    ``(q_i - q_k) / d_ik`` and ``coll_logd`` the log-derivative ``G'/G``.
    """

    n: int
    pairs: np.ndarray
    pair_factor: np.ndarray
    dP_di: np.ndarray
    dP_dj: np.ndarray
    clearance_m: np.ndarray
    collision: np.ndarray
    coll_pairs: np.ndarray
    coll_unit: np.ndarray
    coll_logd: np.ndarray

    # the kernels' W and dense Laplacian, when they computed them (same bits)
    _weights: np.ndarray | None = field(default=None, repr=False, compare=False)
    _laplacian: np.ndarray | None = field(default=None, repr=False, compare=False)
    # (guess, method, lambda2, vector, potential, force) found by the same kernel call: the
    # result of fiedler(guess=guess, method=method) and of exact_force for ``potential``
    # ((lambda2_min, lambda2_null, gain); force None if not made)
    _eigen: tuple | None = field(default=None, repr=False, compare=False)

    @property
    def weights(self) -> np.ndarray:
        """``W_ij = P_ij C_i C_j`` per pair."""
        if self._weights is not None:
            return self._weights
        return (
            self.pair_factor * self.collision[self.pairs[:, 0]] * self.collision[self.pairs[:, 1]]
        )

    def cached_force(
        self, lambda2: float, nu: np.ndarray, params: ConnectivityParams
    ) -> np.ndarray | None:
        """The force of eq. (17) for exactly this eigenpair and ``params``'s potential, if
        the weights' kernel call made it (:func:`compute_weights` with ``with_force``)."""
        eigen = self._eigen
        if eigen is None or eigen[5] is None or nu is not eigen[3] or lambda2 != eigen[2]:
            return None
        if eigen[4] != (params.lambda2_min, params.lambda2_null, params.potential_gain):
            return None
        return eigen[5]

    def active(self) -> tuple[np.ndarray, np.ndarray]:
        """Pairs with ``W_ij > 0`` and their weights (the graph ``G_lambda``)."""
        w = self.weights
        keep = w > 0
        return self.pairs[keep], w[keep]

    def laplacian_dense(self) -> np.ndarray:
        """Dense weighted Laplacian ``L = diag(W 1) - W``."""
        return laplacian_dense(self.n, self.pairs, self.weights)

    def fiedler(
        self,
        *,
        guess: np.ndarray | None = None,
        state: WarmState | None = None,
        method: Method = "auto",
    ) -> tuple[float, np.ndarray]:
        """Exact lambda2 and unit Fiedler vector of ``G_lambda`` (:func:`tether.graph.fiedler`).

        ``guess`` (a previous Fiedler vector) fixes the sign of the result and is the
        certified warm start (``auto``: from 17 robots); ``state`` keeps the large-team
        warm solver's factorization between steps; ``method`` as ``fiedler``'s
        (``"lapack"``: LAPACK only up to 400 robots, the choice before the small solver).
        """
        eigen = self._eigen
        if eigen is not None and guess is eigen[0] and method == eigen[1]:
            return eigen[2], eigen[3]
        w = self.weights
        lap = self._laplacian
        if lap is None and jit.enabled() and self.n <= SUBSET_MAX_N:  # compiled, same matrix
            from tether.graph.kernels import laplacian_dense_kernel

            lap = laplacian_dense_kernel(self.n, self.pairs, w)
        return fiedler(self.n, self.pairs, w, guess=guess, laplacian=lap, state=state,
                       method=method)  # fmt: skip


def collision_factor(n: int, coll_pairs: np.ndarray, gamma: np.ndarray) -> np.ndarray:
    """``C_i = prod_k G(d_ik)`` per robot from the pair values ``G`` (1 if no pair)."""
    logc = np.zeros(n)
    zero = np.zeros(n, dtype=bool)
    if len(coll_pairs):
        lg = floats.log(gamma)  # the C library's, as the kernel's (-inf where gamma = 0)
        finite = gamma > 0
        np.add.at(logc, coll_pairs[finite, 0], lg[finite])
        np.add.at(logc, coll_pairs[finite, 1], lg[finite])
        zero[coll_pairs[~finite, 0]] = True
        zero[coll_pairs[~finite, 1]] = True
    return np.where(zero, 0.0, floats.exp(logc))


def compute_weights(
    positions: np.ndarray,
    params: ConnectivityParams,
    obstacles: ObstacleIndex | None = None,
    pairs: np.ndarray | None = None,
    guess: np.ndarray | None = None,
    method: Method = "auto",
    with_force: bool = False,
) -> WeightedGraph:
    """The weighted graph ``G_lambda`` of the team (App. A, steps 1-2).

    Parameters
    ----------
    positions
        ``(n, dim)`` robot positions.
    params
        Table 2 parameters.
    obstacles
        Obstacle index (``None``: free space).
    pairs
        Optional precomputed pairs within ``Rs`` (``i < j``); found with a
        k-d tree otherwise.
    guess
        The Fiedler vector the caller will pass to :meth:`WeightedGraph.fiedler`: with
        the kernels, a team of ``2 <= n <= SUBSET_MAX_N`` robots gets its
        eigenpair in the same compiled call as its weights
        (:func:`tether.continuous.connectivity.kernels.evaluate_fiedler_kernel`);
        ``fiedler(guess=guess, method=method)`` then returns it (the same bits as
        computing it there).
    method
        The ``fiedler`` method that eigenpair is for: ``"auto"`` or ``"lapack"``.
    with_force
        With that eigenpair, the force of eq. (17) too (in the same call):
        :func:`tether.continuous.connectivity.gradient.exact_force` then returns it (same bits).

    With :func:`tether.jit.enabled`, the kernels of :mod:`tether.continuous.connectivity.kernels`
    compute the same arrays (to the last bit) without numpy's per-call overhead.
    """
    q = np.asarray(positions, dtype=float)
    if obstacles is not None and obstacles.tree is None:
        # an index without points is free space: B = S(inf) = 1 and dB = 0, so the obstacle
        # branch gives the same numbers (up to the sign of zeros), at twice the cost
        obstacles = None
    if jit.enabled():
        if pairs is None:
            return _evaluate_kernel(q, params, obstacles, guess, method, with_force)
        return _compute_weights_kernel(q, params, obstacles, pairs)
    return _compute_weights_reference(q, params, obstacles, pairs)


def _compute_weights_kernel(
    q: np.ndarray,
    params: ConnectivityParams,
    obstacles: ObstacleIndex | None,
    pairs: np.ndarray,
) -> WeightedGraph:
    """:func:`compute_weights` of given pairs by the kernels of
    :mod:`tether.continuous.connectivity.kernels` (same bits)."""
    from tether.continuous.connectivity import kernels as k

    q = np.ascontiguousarray(q)
    n = len(q)
    pairs = k.pairs_below(q, np.asarray(pairs, dtype=np.int64).reshape(-1, 2), params.rs_m)
    has_obstacles = obstacles is not None and len(pairs) > 0
    if has_obstacles:
        i, j = pairs[:, 0], pairs[:, 1]
        clear, s_star, o_star = obstacles.segment_clearance(
            q[i], q[j], params.ro_outer_m, keys=i * n + j
        )
    else:
        clear, s_star, o_star = _NO_CLEARANCE
    pf, dP_di, dP_dj, clear, coll, coll_pairs, coll_unit, coll_logd = k.weights_kernel(
        q, pairs, has_obstacles, clear, s_star, o_star, params.rs_inner_m, params.rs_m,
        params.ro_m, params.ro_outer_m, params.rc_m, params.rc_outer_m,
    )  # fmt: skip
    return WeightedGraph(n, pairs, pf, dP_di, dP_dj, clear, coll, coll_pairs, coll_unit,
                         coll_logd)  # fmt: skip


_NO_CLEARANCE = (np.zeros(0), np.zeros(0), np.zeros((0, 3)))


@cache
def _kernels() -> tuple:
    """``evaluate_kernel``, ``evaluate_fiedler_kernel``, ``evaluate_fiedler_free_kernel``
    and ``no_obstacles``, imported on first use (numba only when kernels run; an import
    statement in the hot function costs microseconds per call)."""
    from tether.continuous.connectivity import kernels as k

    return k.evaluate_kernel, k.evaluate_fiedler_kernel, k.evaluate_fiedler_free_kernel, \
        k.no_obstacles  # fmt: skip


def _evaluate_kernel(
    q: np.ndarray,
    params: ConnectivityParams,
    obstacles: ObstacleIndex | None,
    guess: np.ndarray | None = None,
    method: Method = "auto",
    with_force: bool = False,
) -> WeightedGraph:
    """Pairs, clearance, weights, ``W``, the dense Laplacian (and with ``guess`` the
    eigenpair, with ``with_force`` the force) in one kernel call."""
    evaluate_kernel, evaluate_fiedler_kernel, evaluate_fiedler_free_kernel, no_obstacles = \
        _kernels()  # fmt: skip
    q = np.ascontiguousarray(q)
    n, dim = q.shape
    has = obstacles is not None and obstacles.tree is not None and n > 1
    estimate = min(n * (n - 1) // 2, 32 * n)
    slack = obstacles.cache_slack_m if has else 0.0
    radii = (params.rs_inner_m, params.rs_m, params.ro_m, params.ro_outer_m, params.rc_m,
             params.rc_outer_m)  # fmt: skip
    fused = (guess is not None and 2 <= n <= SUBSET_MAX_N and len(guess) == n
             and method in ("auto", "lapack"))  # fmt: skip
    if fused:
        guess_c = np.ascontiguousarray(guess, dtype=float)
        potential = (params.lambda2_min, params.lambda2_null, params.potential_gain)
        lwork, liwork = _syevr_lwork(n)
    eigen = None
    for _ in range(2):
        if fused and not has:  # the fused call without an obstacle state to pass
            out, (decided, lam, vec, _), force = evaluate_fiedler_free_kernel(
                q, *radii, guess_c, method == "lapack", small.SETTINGS, lwork, liwork,
                potential, with_force,
            )  # fmt: skip
        else:
            points, tree, table, used, fld = obstacles.kernel_state(estimate) if has else \
                no_obstacles(dim)  # fmt: skip
            if fused:
                out, (decided, lam, vec, _), force = evaluate_fiedler_kernel(
                    q, *radii, has, points, tree, table, used, slack, fld, einsum_order(),
                    guess_c, method == "lapack", small.SETTINGS, lwork, liwork, potential,
                    with_force,
                )  # fmt: skip
            else:
                out = evaluate_kernel(q, *radii, n <= SUBSET_MAX_N, has, points, tree, table,
                                      used, slack, fld, einsum_order())  # fmt: skip
        if fused and decided:
            eigen = (guess, method, lam, vec, potential, force if with_force else None)
        if out[-1] >= 0:
            break
        estimate = len(out[8])
        obstacles.kernel_grow(estimate)
    pf, dP_di, dP_dj, clear, coll, coll_pairs, coll_unit, coll_logd, pairs, w, lap, added = out
    if has:
        obstacles.kernel_added(added)
    return WeightedGraph(n, pairs, pf, dP_di, dP_dj, clear, coll, coll_pairs, coll_unit,
                         coll_logd, w, lap if n <= SUBSET_MAX_N else None, eigen)  # fmt: skip


def _compute_weights_reference(
    q: np.ndarray,
    params: ConnectivityParams,
    obstacles: ObstacleIndex | None,
    pairs: np.ndarray | None,
) -> WeightedGraph:
    """The numpy reference of :func:`compute_weights`."""
    n, dim = q.shape
    if pairs is None:
        pairs = pairs_within(q, params.rs_m)
    pairs = np.asarray(pairs, dtype=np.intp).reshape(-1, 2)
    i, j = pairs[:, 0], pairs[:, 1]
    diff = q[i] - q[j]
    d = np.linalg.norm(diff, axis=1)
    keep = d < params.rs_m
    pairs, i, j, diff, d = pairs[keep], i[keep], j[keep], diff[keep], d[keep]
    u = diff / np.maximum(d, 1e-300)[:, None]
    # A(d) = 1 - S(d) = S(R's + Rs - d) by symmetry; the mirrored form keeps tiny values exact
    a_fac, da = smooth_step(params.rs_inner_m + params.rs_m - d, params.rs_inner_m, params.rs_m)
    da = -da
    dP_di = da[:, None] * u
    clearance = np.full(len(pairs), np.inf)
    b_fac = np.ones(len(pairs))
    if obstacles is not None and len(pairs):
        clearance, s_star, o_star = obstacles.segment_clearance(
            q[i], q[j], params.ro_outer_m, keys=i.astype(np.int64) * n + j
        )
        near = np.isfinite(clearance)
        b_fac, db = smooth_step(
            np.where(near, clearance, params.ro_outer_m), params.ro_m, params.ro_outer_m
        )
        p_star = q[i] + s_star[:, None] * (q[j] - q[i])
        grad_d = (p_star - o_star) / np.maximum(clearance, 1e-300)[:, None]
        grad_d[~near] = 0.0
        dB_di = (db * (1.0 - s_star))[:, None] * grad_d
        dB_dj = (db * s_star)[:, None] * grad_d
        dP_di = dP_di * b_fac[:, None] + a_fac[:, None] * dB_di
        dP_dj = -da[:, None] * u * b_fac[:, None] + a_fac[:, None] * dB_dj
    else:
        dP_dj = -dP_di
    close = d < params.rc_outer_m
    coll_pairs = pairs[close]
    gamma, _ = smooth_step(d[close], params.rc_m, params.rc_outer_m)
    return WeightedGraph(
        n=n,
        pairs=pairs,
        pair_factor=a_fac * b_fac,
        dP_di=dP_di,
        dP_dj=dP_dj,
        clearance_m=clearance,
        collision=collision_factor(n, coll_pairs, gamma),
        coll_pairs=coll_pairs,
        coll_unit=u[close],
        coll_logd=smooth_step_log_derivative(d[close], params.rc_m, params.rc_outer_m),
    )
