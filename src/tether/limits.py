"""How much memory a run may ask for, so that a too-large request is refused up front.

A scenario can ask for more than the machine has (100,000 robots each keeping
its own map, a recording of every link at every step); tether estimates what a
run needs before it starts and refuses with one line naming the field, instead
of swapping or being killed half-way. The allowance is half of the machine's
physical memory, or ``TETHER_MEMORY_LIMIT_GB`` if set.
"""

from __future__ import annotations

import os

from tether.errors import TetherError

__all__ = ["format_bytes", "memory_budget_bytes"]

_FALLBACK_BYTES = 8 * 2**30


def memory_budget_bytes() -> int:
    """The memory one run may use: ``TETHER_MEMORY_LIMIT_GB``, else half the physical memory."""
    limit = os.environ.get("TETHER_MEMORY_LIMIT_GB")
    if limit:
        try:
            value = float(limit)
        except ValueError:
            value = float("nan")
        if not 0 < value < 2**40:
            raise TetherError(
                f"TETHER_MEMORY_LIMIT_GB: must be a positive number of GiB (got {limit!r}); "
                "set it to e.g. 8, or unset it"
            )
        return int(value * 2**30)
    try:
        total = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):  # not POSIX
        return _FALLBACK_BYTES
    return int(total // 2) if total > 0 else _FALLBACK_BYTES


def format_bytes(n: float) -> str:
    """``n`` bytes as ``"27.0 GiB"``, ``"512 MiB"``, ..."""
    for unit, size in (("TiB", 2**40), ("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if n >= size:
            return f"{n / size:.1f} {unit}"
    return f"{int(n)} B"
