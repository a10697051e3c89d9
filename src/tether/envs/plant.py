"""How an action moves a robot: a velocity command, bounded, stopped by obstacles and walls.

An action is a robot's velocity as a fraction of its speed bound, ``(dim,)`` in
``[-1, 1]``; a vector longer than 1 is scaled back to length 1. In one step of
``sim.dt_s`` the robot moves by ``action * max_speed_mps * dt_s`` in a straight line.
A move whose segment meets an obstacle, or ends outside the world's box, is halved
(direction kept) until it is clear, at most 12 times, then dropped: the same rule the
``silent`` strategy's robots obey among obstacles. Such robots are counted as
``blocked``.
"""

from __future__ import annotations

import numpy as np

from tether.world.world import World

#: an action vector longer than this is scaled back to length 1
NORM_TOLERANCE = 1e-9


def row_norms(x: np.ndarray) -> np.ndarray:
    """Euclidean norm of each row, its squares summed in coordinate order (as the kernels)."""
    acc = x[:, 0] * x[:, 0]
    for c in range(1, x.shape[1]):
        acc = acc + x[:, c] * x[:, c]
    return np.sqrt(acc)


def bounded(actions: np.ndarray) -> np.ndarray:
    """``actions`` with every row no longer than 1 (longer rows scaled to length 1)."""
    norm = row_norms(actions)
    long = norm > 1.0 + NORM_TOLERANCE
    if not long.any():
        return actions
    out = actions.copy()
    out[long] /= norm[long, None]
    return out


def move(
    world: World, q: np.ndarray, actions: np.ndarray, step_m: float
) -> tuple[np.ndarray, np.ndarray]:
    """New positions after ``actions`` (bounded), and which robots were blocked."""
    disp = actions * step_m
    q_new = q + disp
    blocked = np.zeros(len(q), dtype=bool)
    if not world.has_obstacles and world.bounds_m is None:
        return q_new, blocked
    active = np.sqrt(np.einsum("kd,kd->k", disp, disp)) > 0
    for _ in range(12):
        idx = np.flatnonzero(active)
        if len(idx) == 0:
            break
        end = q[idx] + disp[idx]
        ok = world.segments_clear(q[idx], end) & world.points_free(end)
        active[idx[ok]] = False
        bad = idx[~ok]
        blocked[bad] = True
        disp[bad] *= 0.5
    disp[active] = 0.0
    if blocked.any():
        q_new[blocked] = q[blocked] + disp[blocked]
    return q_new, blocked


def landing_actions(q: np.ndarray, q_next: np.ndarray, step_m: float) -> tuple[np.ndarray, int]:
    """Actions that move ``q`` to ``q_next`` exactly (bit for bit) in free space.

    ``(q_next - q) / step_m`` lands within a rounding error; each coordinate is then moved
    by one floating-point step at a time towards the action that lands exactly (the
    landing point ``q + a * step_m`` never decreases as ``a`` grows). Returns the actions
    and the number of coordinates that could not be made exact (0 in practice).
    """
    a = (q_next - q) / step_m
    off = np.zeros(q.shape, dtype=bool)
    for _ in range(64):
        land = q + a * step_m
        off = land != q_next
        if not off.any():
            break
        a[off] = np.nextafter(a[off], np.where(land[off] < q_next[off], np.inf, -np.inf))
    return a, int(off.sum())
