"""Compiled smooth steps of :mod:`tether.continuous.connectivity.potential` (numba, lazy).

``S(x; lo, hi)`` with its derivative (:func:`smooth_step1`) and its log-derivative
(:func:`log_derivative1`), one value at a time, with the arithmetic of the numpy
reference in the same order (``scipy.special.expit(x)`` is ``1 / (1 + exp(-x))``), so
the same bits; the kernels of :mod:`tether.continuous.connectivity.kernels` build the weights of
App. A from them. (Over a whole array in phases, divisions first and each ``exp`` in
its own loop, they were no faster for 200 links: the scalar loop already overlaps.)
"""

from __future__ import annotations

import math

from numba import njit


@njit(cache=True, inline="always")
def _band(x, lo, hi):  # noqa: ANN001, ANN202
    """``(inside, t, g, c, width)``: ``t = (x - lo) / width`` and, for ``0 < t < 1``,
    ``g = 1/t - 1/(1 - t)`` and ``c = 1/t^2 + 1/(1 - t)^2`` (0 outside the band)."""
    width = hi - lo
    t = (x - lo) / width
    if t > 0.0 and t < 1.0:
        return (
            True,
            t,
            1.0 / t - 1.0 / (1.0 - t),
            1.0 / (t * t) + 1.0 / ((1.0 - t) * (1.0 - t)),
            width,
        )
    return False, t, 0.0, 0.0, width


@njit(cache=True, inline="always")
def smooth_step1(x, lo, hi):  # noqa: ANN001, ANN202
    """``(S(x; lo, hi), dS/dx)`` of :func:`tether.continuous.connectivity.potential.smooth_step`."""
    inside, t, g, c, width = _band(x, lo, hi)
    if inside:
        s_in = 1.0 / (1.0 + math.exp(g))  # expit(-g)
        e_g = 1.0 / (1.0 + math.exp(-g))  # expit(g)
        return s_in, s_in * e_g * c / width
    return (1.0 if t >= 1.0 else 0.0), 0.0


@njit(cache=True, inline="always")
def log_derivative1(x, lo, hi):  # noqa: ANN001, ANN202
    """``S'(x) / S(x)`` of
    :func:`tether.continuous.connectivity.potential.smooth_step_log_derivative`."""
    inside, _, g, c, width = _band(x, lo, hi)
    if inside:
        return 1.0 / (1.0 + math.exp(-g)) * c / width
    return 0.0
