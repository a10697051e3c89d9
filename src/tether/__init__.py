"""tether: multi-robot teams that stay connected while they navigate and explore."""

from __future__ import annotations

__version__ = "0.1.0"

__all__ = ["__version__"]
