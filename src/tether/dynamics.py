"""Motion models shared by the strategies."""

from __future__ import annotations

import numpy as np


def single_integrator(positions: np.ndarray, displacement: np.ndarray) -> np.ndarray:
    """Kinematic step ``X(t + dt) = X(t) + dX``: the robot reaches its local target."""
    return positions + displacement


def clip_norm(v: np.ndarray, max_norm: np.ndarray | float) -> np.ndarray:
    """Scale rows of ``v`` down so that ``||v_i|| <= max_norm_i`` (direction kept)."""
    norm = np.linalg.norm(v, axis=1)
    scale = np.minimum(1.0, np.asarray(max_norm) / np.maximum(norm, 1e-300))
    return v * scale[:, None]
