"""The sensor's random errors drawn in compiled code, as numpy's ``Generator`` draws them.

:func:`tether.sensing.robots._noisy` draws, for ``k`` measurements, the radial errors,
the angular errors (``rng.uniform`` within the bounds, or a bound with a random sign:
``rng.choice([-1, 1])``) and, in 2-D, the perpendicular's signs. Three ``Generator``
calls cost more than the 20-robot team's arithmetic; :func:`sensor_errors_kernel` makes
the same draws in one compiled call, through the bit generator's C functions (numpy's
documented ``BitGenerator.ctypes`` interface, which numba's own ``Generator`` support
uses too) and numpy's formulas:

* ``uniform(low, high)``: ``low + (high - low) * next_double()`` (numpy's
  ``random_uniform``);
* ``integers(0, 2)`` (and ``choice`` of two values, which draws it): Lemire's method
  on ``next_uint32()`` with a range of 2, ``(u * 2) >> 32``, which never rejects: the
  top bit of ``u``.

So the values and the generator's state afterwards (the half of a 64-bit word that
``next_uint32`` keeps for the next call included) are those of the numpy calls, for any
bit generator (tests: bit for bit, PCG64, MT19937, Philox, SFC64). Like numba's
``Generator`` support, the draws do not take the ``Generator``'s lock: a ``Generator``
must not be shared between threads while sensing (tether's runs own theirs).
"""

from __future__ import annotations

import ctypes

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

NOISE_CODES = {"none": 0, "uniform": 1, "bound": 2}


@intrinsic
def _next_double(typingctx, fn, state):  # noqa: ANN001, ANN202, ARG001
    """``fn(state)``: the bit generator's ``double next_double(void *state)``."""

    def codegen(context, builder, signature, args):  # noqa: ANN001, ANN202, ARG001
        ptr = ir.IntType(8).as_pointer()
        fnty = ir.FunctionType(ir.DoubleType(), [ptr])
        f = builder.inttoptr(args[0], fnty.as_pointer())
        return builder.call(f, [builder.inttoptr(args[1], ptr)])

    return types.float64(types.int64, types.int64), codegen


@intrinsic
def _next_uint32(typingctx, fn, state):  # noqa: ANN001, ANN202, ARG001
    """``fn(state)``: the bit generator's ``uint32_t next_uint32(void *state)``."""

    def codegen(context, builder, signature, args):  # noqa: ANN001, ANN202, ARG001
        ptr = ir.IntType(8).as_pointer()
        fnty = ir.FunctionType(ir.IntType(32), [ptr])
        f = builder.inttoptr(args[0], fnty.as_pointer())
        return builder.call(f, [builder.inttoptr(args[1], ptr)])

    return types.uint32(types.int64, types.int64), codegen


@njit(cache=True, inline="always")
def _coin(bitgen):  # noqa: ANN001, ANN202
    """``integers(0, 2)``: 1 if the top bit of ``next_uint32()`` is set."""
    return (np.uint64(_next_uint32(bitgen[1], bitgen[2])) * np.uint64(2)) >> np.uint64(32)


@njit(cache=True)
def sensor_errors_kernel(k, noise, radial_m, angular_rad, flips, bitgen):  # noqa: ANN001, ANN201, PLR0913
    """Radial errors, angular errors and (``flips``) the perpendicular's coin flips.

    ``noise``: :data:`NOISE_CODES` (no draws for ``none``); ``bitgen``: the addresses
    ``(next_double, next_uint32, state)`` of :func:`bitgen_addresses`. Draws in
    :func:`~tether.sensing.robots._noisy`'s order: ``k`` radial errors, ``k`` angular
    errors, then ``k`` flips (``0`` or ``1``: the index into ``(-1, 1)``).
    """
    e_r = np.zeros(k)
    e_a = np.zeros(k)
    flip = np.zeros(k if flips else 0, np.uint8)
    if noise == 0:
        return e_r, e_a, flip
    for errors, bound in ((e_r, radial_m), (e_a, angular_rad)):
        if noise == 1:  # uniform(-bound, bound)
            low, span = -bound, bound - (-bound)
            for q in range(k):
                errors[q] = low + span * _next_double(bitgen[0], bitgen[2])
        else:  # bound * choice([-1, 1])
            for q in range(k):
                errors[q] = bound * (1.0 if _coin(bitgen) else -1.0)
    for q in range(len(flip)):
        flip[q] = _coin(bitgen)
    return e_r, e_a, flip


#: the last bit generator seen and its addresses (one object: a run keeps its generator)
_LAST: list = [None, None]


def bitgen_addresses(rng: np.random.Generator) -> np.ndarray:
    """``(next_double, next_uint32, state)`` of ``rng``'s bit generator, as int64.

    From numpy's ``BitGenerator.ctypes``; cached for the last bit generator (which is
    kept alive with them, so the addresses stay valid).
    """
    bg = rng.bit_generator
    if _LAST[0] is not bg:
        c = bg.ctypes
        fns = (c.next_double, c.next_uint32)
        addrs = [ctypes.cast(f, ctypes.c_void_p).value for f in fns] + [c.state_address]
        _LAST[:] = [bg, np.array(addrs, dtype=np.int64)]
    return _LAST[1]


def warm_up() -> None:
    """Compile (or load from numba's cache) the kernel."""
    bitgen = bitgen_addresses(np.random.default_rng(0))
    for noise in (0, 1, 2):
        for flips in (False, True):
            sensor_errors_kernel(3, noise, 0.5, 0.1, flips, bitgen)
