"""Floating point that does not depend on the CPU: what the compiled kernels compute.

A few numpy operations give results a last bit apart from one machine to another:

* numpy runs its own SIMD code for some float64 ufuncs where the CPU has it (AVX-512:
  ``exp``, ``log``, ``tan``, ``arccos``, ... on a few per cent of arguments one unit in
  the last place away from the C library's);
* the ``dot`` of two short vectors and a vector's ``numpy.linalg.norm`` are BLAS calls,
  and OpenBLAS picks its kernel by CPU (on AVX-512 machines one that fuses multiplies and
  adds).

The compiled kernels (numba) call the C library and sum coordinates in order on every
machine, and the reference paths they replace must give the same bits (a run must not
depend on whether, or when, the kernels take over: :mod:`tether.jit`). The reference
paths therefore use these functions: :func:`dot` and :func:`norm` in coordinate order,
and the C library's ``exp``, ``log``, ``cos``, ``sin``, ``tan`` and ``arccos`` -- numpy's
own ufunc where it agrees with the C library on this machine (checked once per process
on 4,096 arguments), else element by element through :mod:`math`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import cache

import numpy as np


def dot(x: np.ndarray, y: np.ndarray) -> float:
    """``sum_d x[d] y[d]`` of two short vectors, summed in coordinate order."""
    acc = 0.0
    for a, b in zip(x.tolist(), y.tolist(), strict=True):
        acc += a * b
    return acc


def norm(v: np.ndarray) -> float:
    """Euclidean norm of a short vector: ``sqrt`` of its squares summed in order.

    The value of ``numpy.linalg.norm(rows, axis=1)`` for each row, and of the kernels'
    row norm.
    """
    acc = 0.0
    for a in v.tolist():
        acc += a * a
    return math.sqrt(acc)


def _as_numpy(f: Callable[[float], float]) -> Callable[[float], float]:
    """``f`` with numpy's answers where :mod:`math` raises (overflow: ``inf``; outside the
    domain: ``nan``; ``log(0)``: ``-inf``)."""

    def g(*t: float) -> float:
        try:
            return f(*t)
        except OverflowError:
            return math.inf
        except ValueError:
            return -math.inf if (t[0] == 0.0 and f is math.log) else math.nan

    return g


_TWO_PI = 2.0 * math.pi
#: (numpy ufunc, the C library's function with numpy's special values, probe intervals:
#: 1,024 uniform arguments in each; ``log`` also on a logarithmic scale)
_FUNCTIONS: dict[str, tuple[np.ufunc, Callable[[float], float], tuple[tuple[float, float], ...]]]
_FUNCTIONS = {
    "exp": (np.exp, _as_numpy(math.exp), ((-60.0, 60.0), (-1.0, 1.0), (-10.0, 0.0), (0.0, 10.0))),
    "log": (np.log, _as_numpy(math.log), ((1e-6, 1.0), (0.5, 2.0), (1.0, 1e3), (1e-300, 1e300))),
    "cos": (np.cos, _as_numpy(math.cos), ((-_TWO_PI, _TWO_PI), (-0.5, 0.5), (0.0, 1.6), (-40, 40))),
    "sin": (np.sin, _as_numpy(math.sin), ((-_TWO_PI, _TWO_PI), (-0.5, 0.5), (0.0, 1.6), (-40, 40))),
    "tan": (np.tan, _as_numpy(math.tan), ((-1.57, 1.57), (-0.5, 0.5), (0.0, 1.5), (1.5, 1.5708))),
    "arccos": (
        np.arccos,
        _as_numpy(math.acos),
        ((-1.0, 1.0), (0.9, 1.0), (-1.0, -0.9), (-0.1, 0.1)),
    ),
}


@cache
def numpy_is_libm(name: str) -> bool:
    """numpy's float64 ``name`` gives the C library's values on this machine.

    Checked on 4,096 arguments in four intervals of the function's usual range (an
    implementation that differs does so on a few per cent of arguments).
    """
    ufunc, libm, intervals = _FUNCTIONS[name]
    rng = np.random.default_rng(0)
    x = np.concatenate([rng.uniform(lo, hi, 1024) for lo, hi in intervals])
    if name == "log":
        x[-1024:] = np.geomspace(1e-300, 1e300, 1024)
    return bool(np.array_equal(ufunc(x), np.array([libm(t) for t in x.tolist()])))


def _apply(name: str, x: np.ndarray | float) -> np.ndarray:
    ufunc, libm, _ = _FUNCTIONS[name]
    if numpy_is_libm(name):
        return ufunc(x)
    a = np.asarray(x, dtype=float)
    out = np.fromiter(map(libm, a.ravel().tolist()), dtype=float, count=a.size)
    return out.reshape(a.shape)


def exp(x: np.ndarray | float) -> np.ndarray:
    """The C library's ``exp``, element by element."""
    return _apply("exp", x)


def log(x: np.ndarray | float) -> np.ndarray:
    """The C library's ``log``, element by element (arguments must be > 0)."""
    return _apply("log", x)


def cos(x: np.ndarray | float) -> np.ndarray:
    """The C library's ``cos``, element by element."""
    return _apply("cos", x)


def sin(x: np.ndarray | float) -> np.ndarray:
    """The C library's ``sin``, element by element."""
    return _apply("sin", x)


def tan(x: np.ndarray | float) -> np.ndarray:
    """The C library's ``tan``, element by element."""
    return _apply("tan", x)


def power(x: np.ndarray | float, p: float) -> np.ndarray:
    """The C library's ``pow(x, p)``, element by element (``p`` a scalar)."""
    a = np.asarray(x, dtype=float)
    if _power_is_libm():
        return np.power(a, p)
    pw = _as_numpy(math.pow)
    out = np.fromiter((pw(t, p) for t in a.ravel().tolist()), dtype=float, count=a.size)
    return out.reshape(a.shape)


@cache
def _power_is_libm() -> bool:
    """numpy's float64 ``power`` gives the C library's ``pow`` here (4,096 pairs in
    ``[0, 1] x [1, 4]``, the range of eqs. (14)-(15), and wider)."""
    rng = np.random.default_rng(0)
    x = np.concatenate([rng.uniform(0, 1, 2048), rng.uniform(0, 100, 2048)])
    p = np.concatenate([rng.uniform(1, 4, 2048), rng.uniform(-3, 3, 2048)])
    return bool(np.array_equal(np.power(x, p), [math.pow(a, b) for a, b in zip(x, p, strict=True)]))


def arccos(x: np.ndarray | float) -> np.ndarray:
    """The C library's ``acos``, element by element (arguments in ``[-1, 1]``)."""
    return _apply("arccos", x)
