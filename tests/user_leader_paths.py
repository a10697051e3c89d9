"""A user's module of leader paths, as a scenario's ``trajectory.function`` names one.

Its name starts with a letter, as a user's module does: tether refuses functions of
modules that belong to Python, tether or its libraries (private ``_name`` modules too).
"""

from __future__ import annotations

import numpy as np


def leader_circle(t_s: float) -> list[float]:
    """A leader's path as a function of time (``trajectory.kind: function``)."""
    return [10.0 * np.cos(0.05 * t_s), 10.0 * np.sin(0.05 * t_s)]
