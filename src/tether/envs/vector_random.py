"""``np.random.default_rng(seed)``'s stream, compiled (numba), for many seeds in one call.

:mod:`.vector_placement` places the teams of many copies in one compiled call, each
from its own seed, and must draw exactly the numbers ``tether run --seed`` draws. A
``numpy.random.Generator`` cannot be made inside numba, and making one per copy in
Python costs more than placing its team; so the stream is computed here from the seed,
step by step as numpy computes it:

* :func:`seed_state`: ``SeedSequence(seed)`` (the hash of the seed's 32-bit words into
  a pool of four, then 256 bits of state) and ``PCG64``'s seeding (state and increment
  of the 128-bit LCG);
* :func:`next64`: ``PCG64``'s output (XSL-RR of the 128-bit state, emulated with two
  64-bit halves); :func:`next32` keeps the unused half as numpy's bit generator does;
* the draws of ``Generator``: :func:`next_double` (``random``, ``uniform``),
  :func:`bounded` (``integers``: Lemire's rejection on 32-bit words),
  :func:`standard_normal` (the ziggurat, with numpy's tables as numba ships them).

A state is a ``uint64`` array of :data:`STATE_WORDS`: the LCG's state (high, low), its
increment (high, low), whether a 32-bit half is kept, and that half.
``tests/test_envs_placement.py`` compares every draw with numpy's for many seeds.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numba.np.random._constants import (
    fi_double,
    ki_double,
    wi_double,
    ziggurat_nor_inv_r,
    ziggurat_nor_r,
)

STATE_WORDS = 6

_U = np.uint64
M32 = _U(0xFFFFFFFF)
S1, S8, S11, S16, S32, S58, S63 = _U(1), _U(8), _U(11), _U(16), _U(32), _U(58), _U(63)
#: PCG64's multiplier, high and low 64 bits
MULT_HI, MULT_LO = _U(2549297995355413924), _U(4865540595714422341)
#: SeedSequence's hash constants
INIT_A, MULT_A = _U(0x43B0D7E5), _U(0x931E8875)
INIT_B, MULT_B = _U(0x8B51F9DD), _U(0x58F38DED)
MIX_L, MIX_R = _U(0xCA01F9DD), _U(0x4973F715)
POOL = 4
TO_DOUBLE = 1.0 / 9007199254740992.0


@njit(cache=True, inline="always")
def _mulhi(a, b):  # noqa: ANN001, ANN202
    """The high 64 bits of the 128-bit product of two ``uint64``."""
    a_lo, a_hi, b_lo, b_hi = a & M32, a >> S32, b & M32, b >> S32
    p0, p1, p2, p3 = a_lo * b_lo, a_lo * b_hi, a_hi * b_lo, a_hi * b_hi
    mid = (p0 >> S32) + (p1 & M32) + (p2 & M32)
    return p3 + (p1 >> S32) + (p2 >> S32) + (mid >> S32)


@njit(cache=True, inline="always")
def _step(st):  # noqa: ANN001, ANN202
    """state = state * MULT + increment (mod 2**128)."""
    sh, sl = st[0], st[1]
    lo = sl * MULT_LO
    hi = _mulhi(sl, MULT_LO) + sl * MULT_HI + sh * MULT_LO
    new_lo = lo + st[3]
    st[0] = hi + st[2] + (S1 if new_lo < lo else _U(0))
    st[1] = new_lo


@njit(cache=True)
def next64(st):  # noqa: ANN001, ANN201
    """The next 64-bit output (``PCG64.random_raw``)."""
    _step(st)
    x = st[0] ^ st[1]
    rot = st[0] >> S58
    return (x >> rot) | (x << ((_U(64) - rot) & S63))


@njit(cache=True)
def next32(st):  # noqa: ANN001, ANN201
    """The next 32-bit word: the low half of an output, then its kept high half."""
    if st[4]:
        st[4] = 0
        return st[5]
    x = next64(st)
    st[4], st[5] = 1, x >> S32
    return x & M32


@njit(cache=True)
def next_double(st):  # noqa: ANN001, ANN201
    """Uniform in ``[0, 1)`` (``Generator.random``)."""
    return float(next64(st) >> S11) * TO_DOUBLE


@njit(cache=True)
def bounded(st, high):  # noqa: ANN001, ANN201
    """``Generator.integers(high + 1)`` for ``0 <= high < 2**32 - 1`` (no draw if 0)."""
    if high == 0:
        return np.int64(0)
    rng = _U(high)
    excl = rng + S1
    m = next32(st) * excl
    left = m & M32
    if left < excl:
        threshold = (M32 - rng) % excl
        while left < threshold:
            m = next32(st) * excl
            left = m & M32
    return np.int64(m >> S32)


@njit(cache=True)
def standard_normal(st):  # noqa: ANN001, ANN201
    """``Generator.standard_normal`` (numpy's ziggurat)."""
    while True:
        r = next64(st)
        idx = int(r & _U(0xFF))
        r = r >> S8
        rabs = (r >> S1) & _U(0x000FFFFFFFFFFFFF)
        x = float(rabs) * wi_double[idx]
        if r & S1:
            x = -x
        if rabs < ki_double[idx]:
            return x
        if idx == 0:
            while True:
                xx = -ziggurat_nor_inv_r * math.log1p(-next_double(st))
                yy = -math.log1p(-next_double(st))
                if yy + yy > xx * xx:
                    if (rabs >> S8) & S1:
                        return -(ziggurat_nor_r + xx)
                    return ziggurat_nor_r + xx
        elif (fi_double[idx - 1] - fi_double[idx]) * next_double(st) + fi_double[idx] < math.exp(
            -0.5 * x * x
        ):
            return x


@njit(cache=True, inline="always")
def _hashmix(value, const):  # noqa: ANN001, ANN202
    """SeedSequence's ``hashmix``: (mixed value, next hash constant), in 32 bits."""
    value = value ^ const
    const = (const * MULT_A) & M32
    value = (value * const) & M32
    return value ^ (value >> S16), const


@njit(cache=True, inline="always")
def _mix(x, y):  # noqa: ANN001, ANN202
    r = (MIX_L * x - MIX_R * y) & M32
    return r ^ (r >> S16)


@njit(cache=True)
def seed_state(seed, st):  # noqa: ANN001, ANN201
    """Set ``st`` to ``PCG64(SeedSequence(seed))``'s state (``0 <= seed < 2**63``)."""
    words = np.zeros(2, np.uint64)
    s = _U(seed)
    n_words = 1
    words[0] = s & M32
    if s >> S32:
        words[1] = s >> S32
        n_words = 2
    pool = np.zeros(POOL, np.uint64)
    const = INIT_A
    for i in range(POOL):
        pool[i], const = _hashmix(words[i] if i < n_words else _U(0), const)
    for src in range(POOL):
        for dst in range(POOL):
            if src != dst:
                h, const = _hashmix(pool[src], const)
                pool[dst] = _mix(pool[dst], h)
    out = np.zeros(8, np.uint64)  # generate_state(4, uint64): eight 32-bit words
    const = INIT_B
    for i in range(8):
        v = pool[i % POOL] ^ const
        const = (const * MULT_B) & M32
        v = (v * const) & M32
        out[i] = v ^ (v >> S16)
    init_hi, init_lo = out[0] | (out[1] << S32), out[2] | (out[3] << S32)
    seq_hi, seq_lo = out[4] | (out[5] << S32), out[6] | (out[7] << S32)
    st[0], st[1] = 0, 0  # pcg64_srandom: increment 2 * seq + 1, step, add the seed, step
    st[2] = (seq_hi << S1) | (seq_lo >> S63)
    st[3] = (seq_lo << S1) | S1
    _step(st)
    lo = st[1] + init_lo
    st[0] = st[0] + init_hi + (S1 if lo < st[1] else _U(0))
    st[1] = lo
    _step(st)
    st[4], st[5] = 0, 0
