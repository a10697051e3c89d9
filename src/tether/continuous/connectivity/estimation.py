"""Decentralized estimation of lambda2 and the Fiedler vector (Yang et al. 2010).

The continuous-connectivity paper (App. A) computes the connectivity force
from each robot's estimates of lambda2 and of its own Fiedler-vector
component ``nu_2i``, obtained with the estimator of Yang et al. (2010,
"Decentralized estimation and control of graph connectivity for mobile
sensor networks", Automatica 46(2)): a continuous-time power iteration on
the deflated Laplacian whose two global quantities -- the averages of ``x``
and of ``x^2`` -- are tracked by PI average consensus (Freeman et al. 2006).
Robot ``i`` holds ``x_i`` and the consensus states ``(y1_i, w1_i)`` for
``Ave(x)`` and ``(y2_i, w2_i)`` for ``Ave(x^2)``::

    dy1_i = gamma (x_i   - y1_i) - kP sum_j a_ij (y1_i - y1_j) + kI sum_j a_ij (w1_i - w1_j)
    dw1_i =                      - kI sum_j a_ij (y1_i - y1_j)
    (same for y2, w2 with x_i^2)
    dx_i  = -k1 y1_i - k2 sum_j W_ij (x_i - x_j) - k3 (y2_i - 1) x_i

At the stable equilibrium (``k1 > k3 > k2 lambda2``) ``x`` is a Fiedler
vector with ``Ave(x^2) = 1 - k2 lambda2 / k3``, hence the estimates::

    lambda2_i = (k3 / k2) (1 - y2_i),        nu_2i = x_i / sqrt(n y2_i).

If ``lambda2 >= k3 / k2`` the equilibrium is ``x = 0`` and the estimate
saturates at ``k3 / k2``; with the default ``k3 / k2 = 2 lambda2_null`` this
only happens where the potential, and hence the force, is zero anyway.

Gains: the mean of ``x`` and of ``y1`` obey approximately
``s^2 + (gamma - k2 lambda2) s + gamma (k1 - k2 lambda2) = 0``, which is
nearly undamped for ``gamma = 1`` and ``lambda2`` near 1 (we saw slow
oscillations of the estimate); ``gamma = 4``, ``kP = 2``, ``kI = 3`` gave the
fastest reliable convergence in a sweep over random graphs (Yang et al. do
not prescribe values).

We integrate the ODE with forward Euler, one step per communication round;
``a_ij = 1`` on the links of ``G_lambda`` (``W_ij > 0``). Every round each
robot broadcasts ``(x, y1, w1, y2, w2)`` through the
:class:`tether.comm.MessageLayer`, so message loss, delay and robot failure
act on the estimator directly; a receiver uses the last value it got from
each neighbour (and drops the neighbour's term if it never got one).

The Euler step is ``step_scale / (k1 + k3 + gamma + 2 k2 dW + 2 (kP + kI) d)``
with ``dW``/``d`` the largest weighted/unweighted degree, a bound that a
max-consensus provides in a deployment (we read it from the graph), or
``1.1 (2 kI d)^2 / (gamma + 2 kP d)`` if that is larger (never with the default
gains): the PI consensus has oscillating modes, of modulus ``kI mu`` for a Laplacian
eigenvalue ``mu <= 2 d``, which the Euler step keeps decaying only below
``(gamma + kP mu) / (kI mu)^2`` (with ``kI = 12`` and the sum alone the estimates
overflowed within a few hundred rounds).
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp
from pydantic import BaseModel, ConfigDict, Field, model_validator

from tether.comm import CommParams, MessageLayer
from tether.continuous.connectivity.weights import WeightedGraph


class EstimatorParams(BaseModel):
    """Gains of the estimator (dimensionless, per round); the defaults are the ones runs use."""

    model_config = ConfigDict(extra="forbid", frozen=True, allow_inf_nan=False)

    k1: float = 4.0
    k2: float = 1.0
    k3: float = 2.0
    gamma: float = 4.0
    kp: float = 2.0
    ki: float = 3.0
    step_scale: float = Field(default=1.0, gt=0, le=1)

    @model_validator(mode="after")
    def _stable(self) -> EstimatorParams:
        if not (self.k1 > self.k3 > 0 and self.k2 > 0):
            raise ValueError("need k1 > k3 > 0 and k2 > 0 (Yang et al. 2010)")
        if not (self.gamma > 0 and self.kp > 0 and self.ki > 0):
            raise ValueError("need gamma, kp, ki > 0")
        return self

    @property
    def saturation(self) -> float:
        """The largest lambda2 the estimator can report (``k3 / k2``)."""
        return self.k3 / self.k2

    def gains(self) -> EstimatorParams:
        """Only the gains (drops the fields a subclass adds)."""
        return EstimatorParams(**{k: getattr(self, k) for k in EstimatorParams.model_fields})


class FiedlerEstimator:
    """Per-robot estimates of lambda2 and of the unit Fiedler vector.

    Parameters
    ----------
    n
        Team size (known to every robot; it normalises the vector).
    params
        Estimator gains.
    comm
        Message layer (owns loss, delay and failures).
    rng
        Draws the initial ``x`` (a random vector, as in Yang et al.).
    """

    STATE = ("x", "y1", "w1", "y2", "w2")

    def __init__(
        self,
        n: int,
        params: EstimatorParams,
        comm: MessageLayer,
        rng: np.random.Generator,
        x0: np.ndarray | None = None,
    ) -> None:
        self.n = n
        self.params = params
        self.comm = comm
        self.state = np.zeros((n, 5))
        x = rng.normal(size=n) if x0 is None else np.asarray(x0, dtype=float)
        self.state[:, 0] = x
        self.state[:, 1] = x  # y1 starts at the own value of x ...
        self.state[:, 3] = x * x  # ... and y2 at the own value of x^2
        self.rounds = 0

    @classmethod
    def create(
        cls,
        n: int,
        rng: np.random.Generator,
        params: EstimatorParams | None = None,
        comm: CommParams | None = None,
    ) -> FiedlerEstimator:
        """An estimator with its own message layer."""
        layer = MessageLayer(n, comm or CommParams(), rng)
        return cls(n, params or EstimatorParams(), layer, rng)

    def update(self, graph: WeightedGraph, rounds: int = 1) -> None:
        """Run ``rounds`` communication rounds over the links of ``G_lambda``."""
        p = self.params
        pairs, w = graph.active()
        n = self.n
        deg_w = np.bincount(pairs[:, 0], w, n) + np.bincount(pairs[:, 1], w, n)
        deg = np.bincount(pairs.ravel(), minlength=n)
        d = deg.max(initial=0)
        bound = p.k1 + p.k3 + p.gamma + 2 * p.k2 * deg_w.max(initial=0.0) + 2 * (p.kp + p.ki) * d
        # the PI consensus's oscillating modes (module docstring): never with the defaults
        bound = max(bound, 1.1 * (2 * p.ki * d) ** 2 / (p.gamma + 2 * p.kp * d))
        eps = p.step_scale / bound
        gains = np.array(
            [[-p.k2, 0, 0, 0, 0],  # x: weighted Laplacian
             [0, -p.kp, -p.ki, 0, 0],  # y1 <- L y1, w1 <- L y1
             [0, p.ki, 0, 0, 0],  # y1 <- L w1
             [0, 0, 0, -p.kp, -p.ki],
             [0, 0, 0, p.ki, 0]]
        )  # fmt: skip
        if self.comm.perfect:
            self._perfect_rounds(pairs, w, rounds, eps, gains)
            return
        recv_all = np.concatenate([pairs[:, 0], pairs[:, 1]])
        e = len(recv_all)
        # receiver-incidence matrix: (S @ z)_i = sum over i's incoming links of z
        inc = sp.csr_matrix((np.ones(e), (recv_all, np.arange(e))), shape=(n, e))
        w_dir = np.concatenate([w, w])
        for _ in range(rounds):
            inbox = self.comm.exchange(pairs, self.state)
            alive = self.comm.alive(self.comm.round - 1)
            # own minus each neighbour's last received value; 0 where none was received
            diff = self.state[recv_all] - inbox.values
            diff[~inbox.valid] = 0.0
            diff[:, 0] *= w_dir
            lap = inc @ diff  # (n, 5) Laplacian terms: weighted for x, plain for the rest
            x, y1, _, y2, _ = self.state.T
            delta = lap @ gains
            delta[:, 0] += -p.k1 * y1 - p.k3 * (y2 - 1.0) * x
            delta[:, 1] += p.gamma * (x - y1)
            delta[:, 3] += p.gamma * (x * x - y2)
            delta *= eps
            delta[~alive] = 0.0  # a failed robot's estimator is frozen
            self.state += delta
            self.rounds += 1

    def _perfect_rounds(
        self, pairs: np.ndarray, w: np.ndarray, rounds: int, eps: float, gains: np.ndarray
    ) -> None:
        """The same rounds on a perfect message layer, as Laplacian products.

        With every message delivered fresh, ``sum_j (z_i - z_j)`` over the
        received values is ``(L z)_i``; the rounds are then computed from
        two sparse Laplacians (weighted for ``x``, plain for the consensus
        states) without materialising the messages.
        """
        p, n = self.params, self.n
        rows = np.r_[pairs[:, 0], pairs[:, 1]]
        order = np.argsort(rows, kind="stable")
        cols = np.r_[pairs[:, 1], pairs[:, 0]][order]
        indptr = np.r_[0, np.cumsum(np.bincount(rows, minlength=n))]
        adj_w = sp.csr_matrix((np.r_[w, w][order], cols, indptr), shape=(n, n))
        adj = sp.csr_matrix((np.ones(len(rows)), cols, indptr), shape=(n, n))
        deg_w = np.bincount(rows, np.r_[w, w], n)
        deg = np.diff(indptr).astype(float)[:, None]
        lap = np.empty((n, 5))
        for _ in range(rounds):
            x, y1, _, y2, _ = self.state.T
            lap[:, 0] = deg_w * x - adj_w @ x  # weighted Laplacian for x
            lap[:, 1:] = deg * self.state[:, 1:] - adj @ self.state[:, 1:]
            delta = lap @ gains
            delta[:, 0] += -p.k1 * y1 - p.k3 * (y2 - 1.0) * x
            delta[:, 1] += p.gamma * (x - y1)
            delta[:, 3] += p.gamma * (x * x - y2)
            delta *= eps
            self.state += delta
        self.rounds += rounds
        self.comm.perfect_rounds(pairs, rounds)

    @property
    def lambda2(self) -> np.ndarray:
        """Each robot's estimate of lambda2, ``(n,)``."""
        return self.params.saturation * (1.0 - self.state[:, 3])

    @property
    def vector(self) -> np.ndarray:
        """Each robot's estimate of its own unit Fiedler-vector component, ``(n,)``."""
        y2 = np.maximum(self.state[:, 3], 1e-12)
        return self.state[:, 0] / np.sqrt(self.n * y2)


def estimate_errors(
    estimator: FiedlerEstimator, lambda2: float, nu: np.ndarray
) -> tuple[float, float]:
    """Worst relative lambda2 error over robots and worst vector-component error.

    The sign of the estimated vector is free; the better of the two is used.
    """
    lam_err = float(np.max(np.abs(estimator.lambda2 - lambda2)) / max(abs(lambda2), 1e-12))
    v = estimator.vector
    vec_err = float(min(np.max(np.abs(v - nu)), np.max(np.abs(v + nu))))
    return lam_err, vec_err
