"""The external force of strategy ``connectivity`` is never longer than ``magnitude_n``."""

from __future__ import annotations

import numpy as np
import pytest

from tether.continuous.connectivity.external import ExternalForce, external_force


@pytest.mark.parametrize(
    "spec",
    [
        {"kind": "constant", "forces": [[30.0, -40.0]], "magnitude_n": 2.0},
        {"kind": "goal", "robots": [0, 2], "goals": [[100, 0], [0, -80]], "magnitude_n": 3.0},
        {"kind": "random", "magnitude_n": 1.5},
    ],
    ids=["constant", "goal", "random"],
)
def test_every_robot_s_force_is_bounded(spec: dict) -> None:
    q = np.array([[0.0, 0.0], [5.0, 1.0], [2.0, 7.0]])
    for seed in range(20):
        f = external_force(ExternalForce(**spec), q, np.random.default_rng(seed), None)
        assert f.shape == q.shape
        assert (np.linalg.norm(f, axis=1) <= spec["magnitude_n"] * (1 + 1e-12)).all()
    if spec["kind"] != "random":  # the far pulls are saturated to exactly the bound
        assert np.linalg.norm(f, axis=1).max() == pytest.approx(spec["magnitude_n"])


def test_a_goal_within_reach_pulls_with_gain_times_distance() -> None:
    spec = ExternalForce(kind="goal", robots=[1], goals=[[5.5, 1.0]], gain_n_per_m=2.0,
                         magnitude_n=3.0)  # fmt: skip
    q = np.array([[0.0, 0.0], [5.0, 1.0]])
    f = external_force(spec, q, np.random.default_rng(0), None)
    np.testing.assert_allclose(f, [[0.0, 0.0], [1.0, 0.0]])  # 2 N/m x 0.5 m, below 3 N
