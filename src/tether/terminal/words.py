"""Words for counts in plain English."""

from __future__ import annotations


def count(n: int, noun: str, plural: str | None = None) -> str:
    """``1 robot``, ``12 robots``, ``1,000 robots`` (``plural`` for irregular nouns)."""
    return f"{n:,} {noun if n == 1 else plural or noun + 's'}"
