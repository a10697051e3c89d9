"""The smooth step and the connectivity potential ``V(lambda2)`` (App. A, step 3).

Continuous-connectivity paper (Nestmeyer et al., "Decentralized simultaneous
multi-target exploration using a connected network of multiple robots"),
Sec. 2 and Appendix A, after Robuffo Giordano et al. (2013).

The smooth step ``S(x; lo, hi)`` is the standard C-infinity transition::

    t = (x - lo) / (hi - lo),   S = 0 for t <= 0,   S = 1 for t >= 1,
    S = 1 / (1 + exp(1/t - 1/(1 - t)))  for 0 < t < 1.

All its derivatives vanish at both ends, so every weight is C-infinity in the
positions (away from switches of the closest obstacle point), it is exactly 0
/ exactly 1 outside the transition band, and ``S(t) + S(1 - t) = 1``.

Potential
---------
``V(l2) = k_V (l_null - l2)^2 / (l2 - l_min)`` for ``l_min < l2 < l_null``,
0 above ``l_null`` and ``+inf`` at or below ``l_min``: zero above
``lambda2_null``, C1 at ``lambda2_null`` and unbounded as lambda2 falls to
``lambda2_min`` (App. A, step 3). The force is eq. (17)::

    f_lambda_i = -dV/dl2 * dlambda2/dq_i.
"""

from __future__ import annotations

import numpy as np
from scipy.special import expit

from tether.continuous.connectivity.params import ConnectivityParams


def _band(
    x: np.ndarray, lo: float, hi: float
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``t = (x - lo) / (hi - lo)``, where ``0 < t < 1``, ``t`` there (1/2 outside, where it
    is not used) and ``g = 1/t - 1/(1 - t)`` of it: ``S = expit(-g)`` inside the band."""
    t = (np.asarray(x, dtype=float) - lo) / (hi - lo)
    inside = (t > 0.0) & (t < 1.0)
    tc = np.where(inside, t, 0.5)
    return t, inside, tc, 1.0 / tc - 1.0 / (1.0 - tc)


def smooth_step(x: np.ndarray, lo: float, hi: float) -> tuple[np.ndarray, np.ndarray]:
    """``S(x; lo, hi)`` and ``dS/dx`` (see the module docstring)."""
    t, inside, tc, g = _band(x, lo, hi)
    s_in = expit(-g)
    ds_in = s_in * expit(g) * (1.0 / tc**2 + 1.0 / (1.0 - tc) ** 2) / (hi - lo)
    s = np.where(inside, s_in, (t >= 1.0).astype(float))
    ds = np.where(inside, ds_in, 0.0)
    return s, ds


def smooth_step_log_derivative(x: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """``S'(x) / S(x)`` for ``x > lo`` (0 for ``x <= lo`` and ``x >= hi``), without dividing."""
    _, inside, tc, g = _band(x, lo, hi)
    r = expit(g) * (1.0 / tc**2 + 1.0 / (1.0 - tc) ** 2) / (hi - lo)
    return np.where(inside, r, 0.0)


def potential(lambda2: float, params: ConnectivityParams) -> tuple[float, float]:
    """``V(lambda2)`` and ``dV/dlambda2`` (``(inf, -inf)`` at or below ``lambda2_min``)."""
    lo, hi, k = params.lambda2_min, params.lambda2_null, params.potential_gain
    if lambda2 >= hi:
        return 0.0, 0.0
    if lambda2 <= lo:
        return float("inf"), float("-inf")
    a = hi - lambda2
    b = lambda2 - lo
    return k * a * a / b, -k * a * (a + 2.0 * b) / (b * b)


def potential_slope(lambda2: np.ndarray, params: ConnectivityParams) -> np.ndarray:
    """Vectorised ``dV/dlambda2`` (huge but finite at or below ``lambda2_min``)."""
    lo, hi, k = params.lambda2_min, params.lambda2_null, params.potential_gain
    lam = np.asarray(lambda2, dtype=float)
    a = np.maximum(hi - lam, 0.0)
    b = np.maximum(lam - lo, 1e-12)
    return -k * a * (a + 2.0 * b) / (b * b)
