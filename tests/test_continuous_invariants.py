"""Safety invariants of strategy ``connectivity`` under bounded random pulls.

In each of the three scenes of the paper (empty space, town, office; small
versions so that 100 seeds per scene run in seconds) five robots start in the
safe set and are pulled by bounded random external forces (a random direction
and magnitude per robot, redrawn every second). After every control step we
check, with oracles independent of the strategy's own bookkeeping:

* lambda2 of the weighted graph stays above ``lambda2_min``;
* no two robots are closer than ``Rc`` (all pairs, brute force);
* no robot is closer than ``Ro`` to an obstacle point, and no link with a
  positive weight has a line of sight closer than ``Ro`` to an obstacle
  point (exact point-segment distances to every obstacle point nearby).

The first violation fails the test at once, naming the scene, the seed and the step,
so a broken force shows as one failing step, not as the whole block run to the end. A
force that pushes the team apart is kept safe by the integrator's guard, but only by
ever smaller steps (a run that never ends): every block first needs the force alone to
raise lambda2 of a stretched chain (both paths, compiled and reference), and fails at
once when it does not.
"""

from __future__ import annotations

from functools import cache

import numpy as np
import pytest
from scipy.spatial import cKDTree

from tether import jit
from tether.continuous.connectivity.dynamics import IntegratorParams, integrate
from tether.continuous.connectivity.params import ConnectivityParams
from tether.continuous.connectivity.placement import safe_team
from tether.continuous.connectivity.strategy import ConnectivityStrategy, ConnectivityStrategyParams
from tether.continuous.connectivity.weights import compute_weights
from tether.geometry import point_segment_distance
from tether.sim import StepContext, TeamState
from tether.world.clearance import ObstacleIndex
from tether.world.world import World

SEEDS_PER_SCENE = 100
BLOCK = 25
STEPS = 40
DT_S = 0.1
N_ROBOTS = 5

SCENES = {
    # scene: (scene parameters, Table 2 preset, pull magnitude in N, start heights)
    "empty": ({"size_m": (30.0, 30.0), "height_m": 10.0, "resolution_m": 0.75}, "outdoor", 8.0,
              (2.0, 8.0)),
    "town": ({"size_m": (30.0, 30.0), "height_m": 10.0, "resolution_m": 0.5}, "outdoor", 8.0,
             (1.0, 6.0)),
    "office": ({"resolution_m": 0.1}, "office", 4.0, (0.6, 2.4)),
}  # fmt: skip


@cache
def obstacle_index(name: str) -> ObstacleIndex:
    return ObstacleIndex.from_world(scene(name))


@cache
def scene(name: str) -> World:
    from tether.world.scenes import make_scene

    return make_scene(name, 7, **SCENES[name][0])


def params(name: str) -> ConnectivityStrategyParams:
    _, preset, magnitude, _ = SCENES[name]
    return ConnectivityStrategyParams(
        preset=preset, external={"kind": "random", "magnitude_n": magnitude, "hold_s": 1.0}
    )


def check_invariants(
    q: np.ndarray, name: str, tree: cKDTree | None, p: ConnectivityStrategyParams
) -> dict[str, float]:
    """Independent checks; returns the margins."""
    c = p.connectivity()
    world = scene(name)
    d = np.linalg.norm(q[:, None] - q[None], axis=-1)[np.triu_indices(len(q), 1)]
    graph = compute_weights(q, c, obstacle_index(name))
    lam = graph.fiedler()[0]
    out = {"lambda2": lam, "distance": float(d.min()), "clearance": np.inf, "los": np.inf}
    if tree is not None:
        out["clearance"] = float(tree.query(q)[0].min())
        pts = world.obstacle_points
        pairs, _ = graph.active()
        for a, b in pairs:
            mid, half = (q[a] + q[b]) / 2, np.linalg.norm(q[a] - q[b]) / 2
            near = pts[tree.query_ball_point(mid, half + c.ro_m + 1e-9)]
            if len(near):
                rep = np.repeat
                dist = point_segment_distance(near, rep(q[a:a + 1], len(near), 0),
                                              rep(q[b:b + 1], len(near), 0))  # fmt: skip
                out["los"] = min(out["los"], float(dist.min()))
    return out


def lambda2_under_the_force_alone(on: bool) -> list[float]:
    """lambda2 of a stretched 4-robot chain (4.5 m links, R's = 2.5 m) over 5 steps
    of the connectivity force alone (no external force), kernels ``on`` or off."""
    world = World(dim=2)
    p = ConnectivityStrategyParams()
    c = p.connectivity()
    rng = np.random.default_rng(0)
    state = TeamState.at_rest(np.array([[0.0, 0.0], [4.5, 0.0], [9.0, 0.0], [13.5, 0.0]]))
    with jit.using(on):
        strategy = ConnectivityStrategy(p)
        strategy.reset(world, state, rng)
        out = [compute_weights(state.positions, c, None).fiedler()[0]]
        for k in range(5):
            state = strategy.step(StepContext(k, k * DT_S, DT_S, world, state, None, rng))
            out.append(compute_weights(state.positions, c, None).fiedler()[0])
    return out


def force_problems() -> list[str]:
    """Empty when the force alone raises lambda2 at every step, both ways."""
    problems = []
    for on in (False, True):
        lam = lambda2_under_the_force_alone(on)
        if not all(b > a for a, b in zip(lam, lam[1:], strict=False)):
            path = "compiled" if on else "reference"
            problems.append(f"{path} path: lambda2 {[round(x, 4) for x in lam]} does not rise")
    return problems


@pytest.fixture(scope="module")
def force_holds_the_team() -> None:
    """Fails every dependent test at once when the force does not pull the team together."""
    problems = force_problems()
    if problems:
        pytest.fail("the connectivity force alone does not raise lambda2: " + "; ".join(problems))


@pytest.mark.parametrize("on", [False, True])
def test_the_force_alone_raises_lambda2_of_a_stretched_chain(on: bool) -> None:
    lam = lambda2_under_the_force_alone(on)
    assert all(b > a for a, b in zip(lam, lam[1:], strict=False)), lam


def assert_invariants(m: dict[str, float], c: ConnectivityParams, where: str) -> None:
    """Fail with the place (scene, seed, step) and the margins at the first violation."""
    assert m["lambda2"] > c.lambda2_min, f"{where}: lambda2 {m['lambda2']:.3g} <= lambda2_min"
    assert m["distance"] > c.rc_m, f"{where}: robots {m['distance']:.3g} m apart < Rc {c.rc_m}"
    assert m["clearance"] > c.ro_m, f"{where}: a robot {m['clearance']:.3g} m from an obstacle"
    assert m["los"] > c.ro_m, f"{where}: a line of sight {m['los']:.3g} m from an obstacle"


@pytest.mark.parametrize("block", range(SEEDS_PER_SCENE // BLOCK))
@pytest.mark.parametrize("name", list(SCENES))
@pytest.mark.usefixtures("force_holds_the_team")
def test_random_pulls_keep_the_invariants(name: str, block: int) -> None:
    world = scene(name)
    p = params(name)
    c = p.connectivity()
    pts = world.obstacle_points
    tree = cKDTree(pts) if len(pts) else None
    stretched = 0
    for seed in range(block * BLOCK, (block + 1) * BLOCK):
        rng = np.random.default_rng(seed)
        q0 = safe_team(world, N_ROBOTS, c, rng, margin_m=3.0 if name != "office" else 1.0,
                       height_m=SCENES[name][3])  # fmt: skip
        strategy = ConnectivityStrategy(p)
        state = TeamState.at_rest(q0)
        strategy.reset(world, state, rng)
        assert_invariants(check_invariants(q0, name, tree, p), c, f"{name} seed {seed} start")
        for k in range(STEPS):
            state = strategy.step(StepContext(k, k * DT_S, DT_S, world, state, None, rng))
            m = check_invariants(state.positions, name, tree, p)
            assert_invariants(m, c, f"{name} seed {seed} step {k}")
        d = np.linalg.norm(state.positions[:, None] - state.positions[None], axis=-1)
        stretched += int(d.max() > 2 * c.rs_inner_m)
    assert stretched > 0  # the pulls did pull the teams apart


class _Constant:
    """A System with a constant force whose lambda2 is 0.5 at the start and round-off after."""

    def __init__(self) -> None:
        self.calls = 0

    def evaluate(self, q: np.ndarray) -> tuple[float, None]:
        self.calls += 1
        return (0.5, None) if self.calls == 1 else (1e-16, None)

    def forces(self, q: np.ndarray, v: np.ndarray, cache: None) -> tuple:
        return np.ones_like(q), np.zeros_like(q), np.inf

    def accept(self, q: np.ndarray, v: np.ndarray, cache: None) -> bool:
        return False

    def neighbours(self, cache: None) -> np.ndarray:
        return np.zeros((0, 2), dtype=int)

    def potential(self, lambda2: float) -> float:
        return 0.0


def test_enforce_rejects_a_round_off_lambda2_and_detect_counts_it() -> None:
    """A candidate whose lambda2 is positive only at round-off level left the safe set."""
    q, v = np.zeros((3, 2)), np.zeros((3, 2))
    params = IntegratorParams(guard="enforce", max_retries=3)
    q1, v1, ev, stats = integrate(q, v, 0.1, _Constant(), params, lambda2_min=0.0)
    assert stats.stalls == 1 and stats.guard_interventions == 4 and ev[0] == 0.5
    np.testing.assert_array_equal(q1, q)
    np.testing.assert_array_equal(v1, 0.0)
    params = IntegratorParams(guard="detect")
    q1, v1, ev, stats = integrate(q, v, 0.1, _Constant(), params, lambda2_min=0.0)
    assert stats.guard_interventions == 0 and stats.safe_set_exits == stats.substeps >= 1
    np.testing.assert_allclose(v1, 0.1 / (1 + 0.1 * 2.0))  # one step: nothing vetoed


def test_a_stalled_team_under_enforce_brakes_to_rest() -> None:
    """Moving robots whose every candidate step leaves the safe set stop where they are."""
    q, v = np.zeros((3, 2)), np.array([[1.0, 0.0], [0.0, -2.0], [0.5, 0.5]])
    params = IntegratorParams(guard="enforce", max_retries=3)
    q1, v1, _, stats = integrate(q, v, 0.1, _Constant(), params, lambda2_min=0.0)
    assert stats.stalls == 1
    np.testing.assert_array_equal(q1, q)
    np.testing.assert_array_equal(v1, 0.0)
