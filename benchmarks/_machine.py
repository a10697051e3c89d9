"""Machine description recorded with every benchmark result (see tether.record.machine)."""

from __future__ import annotations

from tether.runfolder import machine

__all__ = ["machine"]
