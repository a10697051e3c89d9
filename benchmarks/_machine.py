"""Machine description recorded with every benchmark result (see tether.runfolder.machine)."""

from __future__ import annotations

from tether.runfolder import machine

__all__ = ["machine"]
