"""Connected navigation without communication (Kerestecioglu & Cezayirli)."""

from __future__ import annotations

from tether.silent.steering import constrained_steps, desired_steps, step_bounds
from tether.silent.strategy import SilentParams, SilentStrategy

__all__ = ["SilentParams", "SilentStrategy", "constrained_steps", "desired_steps", "step_bounds"]
