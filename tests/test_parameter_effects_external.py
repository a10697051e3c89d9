"""The external force ``f_i`` of eq. (1) in ``connectivity`` (``strategy.params.external``;
:mod:`tether.continuous.connectivity.external`), set from a scenario.

Most runs set ``lambda2_null`` below the row's lambda2 (about 0.58), so the connectivity
force is zero while the row keeps its shape and each robot moves by ``f_i`` alone.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest

from _continuous_runs import moved_m, run, scenario
from _parameter_runs import built
from _parameters import effect
from tether.sim import StepContext


def pushed(external: dict[str, Any], steps: int = 10, **params: Any):  # noqa: ANN201
    """The row under ``external`` with no connectivity force (``lambda2_null`` 0.1)."""
    return run(scenario("connectivity", external=external, lambda2_null=0.1, **params), steps)


def forces_applied(external: dict[str, Any], steps: int, dim: int = 2) -> np.ndarray:
    """``f_i`` of each control period, ``(steps, n, dim)``, stepping the strategy by hand."""
    data = scenario("connectivity", external=external, lambda2_null=0.1)
    if dim == 3:
        data["world"]["dim"] = 3
        data["team"]["init"]["positions"] = [[x, 0.0, 5.0 + x / 3] for x in (0, 3, 6, 9)]
    b = built(data)
    s, state = b.strategy, b.initial
    s.reset(b.world, state, b.rng)
    out = []
    for k in range(steps):
        state = s.step(StepContext(k, 0.1 * k, 0.1, b.world, state, None, b.rng))
        out.append(s._f_ext.copy())
    return np.asarray(out)


def direction(r) -> np.ndarray:  # noqa: ANN001
    """Each robot's unit displacement over the run, ``(n, dim)``."""
    d = r.positions[-1] - r.positions[0]
    return d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-300)


@effect("connectivity:external.kind")
def test_the_kind_picks_who_is_pushed_and_how() -> None:
    assert moved_m(pushed({"kind": "none"})).max() == 0.0
    drift = pushed({"kind": "constant", "forces": [[0.0, 2.0]], "magnitude_n": 2.0})
    np.testing.assert_allclose(direction(drift), [[0.0, 1.0]] * 4, atol=1e-9)
    goal = pushed({"kind": "goal", "robots": [1], "goals": [[3.0, -20.0]], "magnitude_n": 2.0})
    assert moved_m(goal)[1] > 0.3 and np.delete(moved_m(goal), 1).max() == 0.0
    random = pushed({"kind": "random", "magnitude_n": 2.0})
    d = direction(random)
    assert moved_m(random).max() > 0.1 and (d @ d.T).min() < 0.9  # each its own way


@effect("connectivity:external.forces")
def test_forces_are_one_vector_for_all_or_one_per_robot() -> None:
    each = [[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]]
    r = pushed({"kind": "constant", "forces": each, "magnitude_n": 1.0})
    np.testing.assert_allclose(direction(r), each, atol=1e-9)
    shared = pushed({"kind": "constant", "forces": [[-1.0, 1.0]], "magnitude_n": 2.0})
    np.testing.assert_allclose(direction(shared), [[-(0.5**0.5), 0.5**0.5]] * 4, atol=1e-9)


@effect("connectivity:external.magnitude_n")
def test_every_external_force_is_bounded_by_magnitude() -> None:
    """A 10 N push saturated at 1 N or 3 N: the terminal speed of the damping follows."""
    speeds = {}
    for bound in (1.0, 3.0):
        push = {"kind": "constant", "forces": [[10.0, 0.0]], "magnitude_n": bound}
        speeds[bound] = pushed(push, 60).metrics["max_speed_mps"]
        assert speeds[bound] == pytest.approx(bound / 2.0, rel=0.05)  # b = 2 N s/m
    for bound in (0.5, 4.0):
        f = forces_applied({"kind": "random", "magnitude_n": bound, "hold_s": 0.1}, 10)
        norms = np.linalg.norm(f, axis=2)
        assert norms.max() <= bound * (1 + 1e-12) and norms.max() > 0.5 * bound


@effect("connectivity:external.hold_s")
def test_random_pulls_are_redrawn_every_hold_s() -> None:
    for hold_s, draws in ((0.5, 4), (1.0, 2)):
        f = forces_applied({"kind": "random", "magnitude_n": 2.0, "hold_s": hold_s}, 20)
        changes = np.flatnonzero(np.any(np.diff(f, axis=0) != 0, axis=(1, 2))) + 1
        assert len(np.unique(f.reshape(20, -1), axis=0)) == draws
        np.testing.assert_array_equal(changes, np.arange(1, draws) * round(hold_s / 0.1))


@effect("connectivity:external.planar")
def test_planar_pulls_stay_horizontal_in_3d() -> None:
    flat = forces_applied({"kind": "random", "magnitude_n": 2.0, "planar": True}, 3, dim=3)
    free = forces_applied({"kind": "random", "magnitude_n": 2.0}, 3, dim=3)
    assert np.all(flat[..., 2] == 0.0) and np.abs(flat[..., :2]).max() > 0.1
    assert np.abs(free[..., 2]).max() > 0.1


@effect("connectivity:external.robots", "connectivity:external.goals")
def test_the_operator_drags_the_robots_named_to_their_goals() -> None:
    goals = {"kind": "goal", "robots": [0, 3], "goals": [[0.0, 30.0], [9.0, -30.0]],
             "magnitude_n": 2.0}  # fmt: skip
    r = pushed(goals, 20)
    np.testing.assert_allclose(direction(r)[[0, 3]], [[0.0, 1.0], [0.0, -1.0]], atol=1e-6)
    assert moved_m(r)[[1, 2]].max() == 0.0
    other = pushed({**goals, "robots": [1, 2]}, 20)
    assert moved_m(other)[[0, 3]].max() == 0.0 and moved_m(other)[[1, 2]].min() > 0.3


@effect("connectivity:external.gain_n_per_m")
def test_the_goal_spring_grows_with_its_gain_until_the_bound() -> None:
    """10 m from the goal: 0.05 N/m pulls with 0.5 N, 0.2 N/m with 2 N, 1 N/m saturates."""
    f = {gain: forces_applied({"kind": "goal", "robots": [1], "goals": [[3.0, 10.0]],
                               "gain_n_per_m": gain, "magnitude_n": 4.0}, 1)[0, 1]
         for gain in (0.05, 0.2, 1.0)}  # fmt: skip
    assert [float(np.linalg.norm(v)) for v in f.values()] == pytest.approx([0.5, 2.0, 4.0], 1e-2)
