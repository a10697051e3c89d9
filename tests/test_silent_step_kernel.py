"""The whole ``silent`` step in one compiled call against the step made of its parts.

:func:`tether.silent.steering_kernels.silent_step_kernel` (the leader's carrot on its
waypoint path, the team's steps, the integration, the leader's statistics) must give
the bits of :meth:`SilentStrategy.step`'s Python path with the same steering kernel
(``_path = None``): positions, velocities, the leader's progress, travel, blocked steps
and goal flag, step after step. A wrong ``min``/``max`` tie rule, dot-product order or
segment index would show in the positions or the progress. Against the numpy reference
(kernels off: ``arccos``/``cos`` from another library) the steps agree to rounding.
"""

from __future__ import annotations

import numpy as np
import pytest

from tether import jit
from tether.paths.trajectory import Polyline
from tether.sensing import SensorModel, sense
from tether.silent.strategy import SilentStrategy
from tether.sim import StepContext, TeamState
from tether.world.world import World

pytest.importorskip("numba")


def _run(
    fused: bool, seed: int, dim: int, steps: int, path: np.ndarray, **kw: float
) -> tuple[list[np.ndarray], list[np.ndarray], list[float], dict]:
    """A team of 6-25 robots following its leader; per-step positions, velocities, progress."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(6, 26))
    pos = rng.uniform(-12.0, 12.0, (n, dim))
    world = World(dim=dim)
    sensor = SensorModel(15.0, body_radius_m=0.5, radial_error_m=0.45,
                         angular_error_rad=np.radians(12))  # fmt: skip
    strategy = SilentStrategy(d_max_m=15.0, trajectory=Polyline(path), d0_m=8.0,
                              radial_error_m=0.45, angular_error_rad=0.2, **kw)  # fmt: skip
    state = TeamState.at_rest(pos)
    strategy.reset(world, state, rng)
    assert strategy._path is not None  # a waypoint path in free space: the fused call
    if not fused:
        strategy._path = None
    out_pos, out_vel, progress = [], [], []
    for k in range(steps):
        obs = sense(state.positions, sensor, rng, world)
        state = strategy.step(StepContext(k, float(k), 0.5, world, state, obs, rng))
        out_pos.append(state.positions)
        out_vel.append(state.velocities)
        progress.append(strategy.progress_m)
    return out_pos, out_vel, progress, strategy.metrics()


PATHS = {
    "zigzag": [[0, 0], [20, 0], [20, 15], [45, 15]],
    "short": [[0, 0], [3, 1]],  # the leader reaches the end and stays
    "repeated": [[0, 0], [10, 0], [10, 0], [10, 10]],  # a zero-length segment
    "point": [[1, 1]],
}


@pytest.mark.parametrize("name", sorted(PATHS))
@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("seed", range(3))
def test_fused_step_is_the_python_step_bit_for_bit(name: str, dim: int, seed: int) -> None:
    pts = np.array(PATHS[name], dtype=float)
    path = np.concatenate([pts, np.full((len(pts), dim - 2), 2.0)], axis=1)
    kw = [{}, {"max_speed_mps": 1.5, "min_separation_m": 1.0},
          {"search_directions": False, "gamma": 0.3}][seed]  # fmt: skip
    with jit.using(True):
        ref = _run(False, seed, dim, 60, path, **kw)
        fast = _run(True, seed, dim, 60, path, **kw)
    for a, b in zip(ref[0] + ref[1], fast[0] + fast[1], strict=True):
        np.testing.assert_array_equal(b, a)
    assert fast[2] == ref[2]  # the leader's progress, step by step
    assert fast[3] == ref[3]  # travel, blocked steps, reached goal, progress


def test_fused_step_agrees_with_the_numpy_reference() -> None:
    path = np.array(PATHS["zigzag"], dtype=float)
    with jit.using(False):
        ref = _run(False, 7, 2, 1, path)
    with jit.using(True):
        fast = _run(True, 7, 2, 1, path)
    np.testing.assert_allclose(fast[0][0], ref[0][0], rtol=0, atol=1e-12)
    assert fast[2] == ref[2]


def test_obstacles_or_a_function_path_keep_the_python_step() -> None:
    rng = np.random.default_rng(0)
    state = TeamState.at_rest(rng.uniform(0, 5, (4, 2)))
    bounded = World(dim=2, bounds_m=np.array([[-50.0, -50.0], [50.0, 50.0]]))
    for world, traj in ((bounded, Polyline(np.array([[0.0, 0.0], [9.0, 0.0]]))),
                        (World(dim=2), lambda t: np.array([t, 0.0]))):  # fmt: skip
        strategy = SilentStrategy(d_max_m=15.0, trajectory=traj)
        strategy.reset(world, state, rng)
        assert strategy._path is None


@pytest.mark.parametrize("dim", [2, 3])
def test_path_point_and_projection_are_the_polylines(dim: int) -> None:
    """``_at`` and ``_project`` against :class:`Polyline` at the waypoints' exact arc
    lengths (where ``bisect_right`` picks the later segment), beyond both ends, and at
    random points and windows: the same bits."""
    from tether.silent import steering_kernels as sk

    rng = np.random.default_rng(dim)
    pts = np.cumsum(rng.normal(size=(7, dim)) * 3.0, axis=0)
    pts[3] = pts[2]  # a zero-length segment
    poly = Polyline(pts)
    args = (poly.waypoints, poly._seg, poly._cum, poly._seg_len, poly.length_m)
    out = np.empty(dim)
    lengths = [*poly._cum.tolist(), -1.0, poly.length_m + 5.0, *rng.uniform(0, 20, 50)]
    for s in lengths:
        sk._at(*args, float(s), out)
        np.testing.assert_array_equal(out, poly.at(s))
    denom = np.array(poly._denom, dtype=float)
    for _ in range(50):
        point = rng.normal(size=dim) * 8.0
        s_min, window = float(rng.uniform(0, 10)), float(rng.choice([3.0, 30.0, np.inf]))
        got = sk._project(poly.waypoints, poly._seg, denom, poly._cum, poly._seg_len,
                          poly.length_m, point, s_min, window, np.empty(dim))  # fmt: skip
        assert got == poly.project(point, s_min, window)
