"""A team that cannot fit its world is refused at once, and a full world stops the placement.

The fuzzer asked ``multi_target`` for 12,000 robots in the 50 x 70 x 10 m box of the Fig. 9
campaign: the placement ran for hours (50 tries of 2.4 M candidates, each against every
robot placed). Now a team that does not fit even packed densest is refused before any
draw, and the tries stop at a bound on the work (pair distances computed).
"""

from __future__ import annotations

import numpy as np
import pytest

from tether.continuous.connectivity.params import ConnectivityParams
from tether.continuous.connectivity.placement import safe_team
from tether.world.world import World


def box(side_m: float) -> World:
    return World(dim=3, bounds_m=np.array([[0.0, 0.0, 0.0], [side_m, side_m, side_m]]))


PARAMS = ConnectivityParams()  # Table 2 outdoor: R'c = 2.5 m


def test_a_team_that_cannot_fit_packed_densest_is_refused_before_any_draw():
    rng = np.random.default_rng(0)
    state = rng.bit_generator.state
    with pytest.raises(ValueError, match=r"do not fit.*at most about \d+"):
        safe_team(box(10.0), 500, PARAMS, rng)
    assert rng.bit_generator.state == state  # refused before a single random draw


def test_a_full_world_stops_at_the_work_bound(monkeypatch):
    """A team that fits packed densest but not by random growth is refused, naming the fill."""
    monkeypatch.setattr("tether.continuous.connectivity.placement.MAX_PAIR_CHECKS", 5_000_000)
    with pytest.raises(ValueError, match="filled up after"):
        safe_team(box(10.0), 150, PARAMS, np.random.default_rng(0), center_m=[5.0, 5.0, 5.0])


def test_a_crowded_start_that_needs_many_tries_is_still_placed():
    """The Fig. 9 office team of 25 jams from its start in up to 14 tries out of 15; a stop
    after a few jammed tries refused a campaign that runs."""
    from tether.config import load_scenario
    from tether.quicksize import load_scenario_at
    from tether.runner import build

    path = load_scenario_at("paper/continuous_fig9_office").source
    sc = load_scenario(path)
    sc.team.n_robots = 25
    for seed in range(10):
        assert build(sc, seed).initial.n == 25


def test_a_team_that_fits_is_placed_as_before():
    rng = np.random.default_rng(3)
    q = safe_team(box(20.0), 30, PARAMS, rng, center_m=[10.0, 10.0, 10.0])
    assert q.shape == (30, 3)
    d = np.linalg.norm(q[:, None] - q[None], axis=2) + np.eye(30) * 1e9
    assert d.min() > PARAMS.rc_outer_m
