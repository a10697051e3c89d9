"""Compiled kernels: one switch for every fast path, numba imported only when used.

The hot paths of the strategies (line-of-sight clearance, the weights and gradient of
App. A, closest points on paths) have a compiled kernel next to their reference code.
Both give the same results (tests compare them: exactly for combinatorial results, to
the last bit where the arithmetic is the same). :func:`enabled` decides which one runs:

* ``TETHER_JIT=0`` in the environment, or :func:`set_enabled` (``False``), selects the
  reference (numpy) paths everywhere;
* otherwise the kernels run when numba is importable: always on the strategies' own hot
  paths, and on paths every strategy shares only once numba is loaded (:func:`warm`).

``numba`` is imported by the kernel modules only, and those only when a kernel is first
needed, so a run that never reaches one (``silent``, ``recurrent``) does not pay for the
import. Kernels are compiled with ``cache=True``: the first call in a fresh install
compiles (seconds), later processes load the machine code from numba's cache.
"""

from __future__ import annotations

import importlib.util
import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager

_forced: bool | None = None


def available() -> bool:
    """numba can be imported."""
    return importlib.util.find_spec("numba") is not None


_default: bool | None = None


def enabled() -> bool:
    """The compiled kernels run (see the module docstring)."""
    global _default
    if _forced is not None:
        return _forced
    if _default is None:  # decided once per process (hot paths ask at every call)
        _default = os.environ.get("TETHER_JIT", "1") != "0" and available()
    return _default


def warm() -> bool:
    """The kernels run and numba is already loaded in this process.

    Paths shared by every strategy (line of sight of the sensing graph, the team's
    metrics) use their kernel only then: a strategy without kernels (``silent``,
    ``recurrent``) then never pays numba's start-up (about a second) for them.
    """
    return enabled() and "numba" in sys.modules


def set_enabled(value: bool | None) -> None:
    """Force the kernels on (``True``) or off (``False``); ``None`` restores the default."""
    global _forced
    if value and not available():
        raise RuntimeError("the compiled kernels need numba: pip install numba")
    _forced = value


@contextmanager
def using(value: bool) -> Iterator[None]:
    """Run a block with the kernels on or off (tests and benchmarks compare both)."""
    before = _forced
    set_enabled(value)
    try:
        yield
    finally:
        set_enabled(before)
