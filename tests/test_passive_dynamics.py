"""Eq. (1) is passive, and the integrated team is too: with ``f_i = 0`` the total energy
``E = sum m |v|^2 / 2 + V(lambda2)`` never grows.

The teams start near the barrier (a chain stretched towards ``Rs``, lambda2 about 1e-4,
so ``V`` is thousands of joules and the connectivity force is stiff) with small random
velocities. ``E`` is computed independently of the integrator's bookkeeping: the exact
lambda2 of the configuration
(:func:`tether.continuous.connectivity.weights.compute_weights`) through the potential of
App. A, checked after every control period and at every sub-step.
A step rule that ignores the force's stiffness injects energy here (the chain is thrown
apart and back); the tolerance is 1e-9 of the start energy.
"""

from __future__ import annotations

import numpy as np
import pytest

from tether.continuous.connectivity.potential import potential
from tether.continuous.connectivity.strategy import ConnectivityStrategy, ConnectivityStrategyParams
from tether.continuous.connectivity.weights import compute_weights
from tether.sim import StepContext, TeamState
from tether.world.clearance import ObstacleIndex
from tether.world.scenes import make_scene

N, SPACING_M, DT_S = 10, 5.5, 0.1


def energy(strategy: ConnectivityStrategy, q: np.ndarray, v: np.ndarray) -> float:
    graph = compute_weights(q, strategy.conn, ObstacleIndex.shared(strategy.world))
    lam = graph.fiedler()[0]
    return 0.5 * strategy.integ.mass_kg * float(np.sum(v * v)) + potential(lam, strategy.conn)[0]


def stretched_team(seed: int) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    q = np.zeros((N, 3))
    q[:, 0] = np.arange(N) * SPACING_M
    q[:, 1:] = rng.normal(scale=0.3, size=(N, 2)) + [0.0, 20.0]
    return q + [5.0, 0.0, 0.0], rng.normal(scale=0.5, size=(N, 3))


@pytest.mark.parametrize("seed", range(4))
def test_a_passive_team_released_near_the_barrier_never_gains_energy(seed: int) -> None:
    world = make_scene("free", seed, dim=3)
    strategy = ConnectivityStrategy(ConnectivityStrategyParams(preset="outdoor"))
    q, v = stretched_team(seed)
    rng = np.random.default_rng(seed)
    strategy.reset(world, TeamState(q, v), rng)
    sub_energies: list[float] = []
    accept = strategy.accept

    def recording(qq: np.ndarray, vv: np.ndarray, cache: object) -> bool:
        sub_energies.append(energy(strategy, qq, vv))
        return accept(qq, vv, cache)

    strategy.accept = recording  # every accepted sub-step
    e0 = energy(strategy, q, v)
    assert e0 > 1e3  # near the barrier: V dominates
    tol = 1e-9 * e0
    state, previous = TeamState(q, v), e0
    for k in range(60):
        state = strategy.step(StepContext(k, k * DT_S, DT_S, world, state, None, rng))
        e = energy(strategy, state.positions, state.velocities)
        assert e <= previous + tol, f"seed {seed}, step {k}: E rose from {previous} to {e}"
        previous = e
    rises = np.diff([e0, *sub_energies])
    assert rises.max() <= tol, f"seed {seed}: a sub-step added {rises.max():.3g} J"
    assert previous < 0.1 * e0  # the energy did flow (into motion, then the damping)
    m = strategy.metrics()
    assert m["controller_success"] and m["safe_set_exits"] == 0
    assert m["max_speed_mps"] <= m["speed_bound_mps"]


@pytest.mark.parametrize("seed", range(2))
def test_the_reported_energy_terms_balance_the_team_s_energy(seed: int) -> None:
    """``energy_net_j`` is what the integrator made or lost: with no external force and
    no linear damping (only the speed-limiting damping, whose work the run reports as
    ``speed_limit_work_j``), ``E_end - E_start = energy_net_j - speed_limit_work_j``,
    ``E`` computed here from the configurations."""
    world = make_scene("free", seed, dim=3)
    params = ConnectivityStrategyParams(preset="outdoor", damping_ns_per_m=0.0)
    strategy = ConnectivityStrategy(params)
    q, v = stretched_team(seed)
    rng = np.random.default_rng(seed)
    strategy.reset(world, TeamState(q, v), rng)
    e0, state = energy(strategy, q, v), TeamState(q, v)
    for k in range(20):
        state = strategy.step(StepContext(k, k * DT_S, DT_S, world, state, None, rng))
    change = energy(strategy, state.positions, state.velocities) - e0
    m = strategy.metrics()
    assert m["speed_limit_work_j"] > 0.5 * e0  # the speed bound took most of the energy
    assert m["energy_net_j"] - m["speed_limit_work_j"] == pytest.approx(change, rel=1e-9)
