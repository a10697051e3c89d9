"""The fused sub-step paths give the chain's bits: weights + eigenpair in one kernel call
(``compute_weights(..., guess=nu)``) and the exact force in one call (``exact_force``),
compiled and not, in free space and in the town."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from tether import jit
from tether.continuous.connectivity.gradient import connectivity_force, exact_force, messages
from tether.continuous.connectivity.placement import safe_team
from tether.continuous.connectivity.strategy import ConnectivityStrategyParams
from tether.continuous.connectivity.weights import compute_weights
from tether.world.clearance import ObstacleIndex
from tether.world.scenes import make_scene
from tether.world.world import World

pytestmark = pytest.mark.skipif(not jit.available(), reason="needs numba")

PARAMS = ConnectivityStrategyParams().connectivity()


@pytest.mark.parametrize("method", ["auto", "lapack"])
@pytest.mark.parametrize("scene", ["free", "town"])
def test_fused_weights_eigenpair_and_force_equal_the_chain(scene: str, method: str) -> None:
    if scene == "free":
        world = World(dim=3, bounds_m=np.array([[0.0, 0, 0], [200.0, 200.0, 10.0]]))
    else:
        world = make_scene("town", 0, size_m=(50.0, 70.0), resolution_m=0.25)
    obs = ObstacleIndex.from_world(world)
    rng = np.random.default_rng(2)
    q = safe_team(world, 30, PARAMS, rng, margin_m=5.0, height_m=(1.0, 8.0))
    nu = compute_weights(q, PARAMS, obs).fiedler()[1]
    for _ in range(8):
        q2 = q + rng.normal(0.0, 0.05, q.shape)
        with jit.using(True):
            fused = compute_weights(q2, PARAMS, obs, guess=nu, method=method, with_force=True)
            assert fused._eigen is not None  # the eigenpair came with the weights
            assert fused._eigen[5] is not None  # and the force
            lam, vec = fused.fiedler(guess=nu, method=method)
            chain = compute_weights(q2, PARAMS, obs).fiedler(guess=nu, method=method)
            force = exact_force(fused, lam, vec, PARAMS)
            assert force is fused._eigen[5]
            force_chain = connectivity_force(fused, lam, messages(fused, vec), PARAMS)
        with jit.using(False):
            ref = compute_weights(q2, PARAMS, obs)
            ref_lam, ref_vec = ref.fiedler(guess=nu, method=method)
            ref_force = exact_force(ref, ref_lam, ref_vec, PARAMS)
        for name in ("pairs", "pair_factor", "dP_di", "dP_dj", "clearance_m", "collision",
                     "coll_pairs", "coll_unit", "coll_logd", "weights"):  # fmt: skip
            assert np.array_equal(getattr(fused, name), getattr(ref, name)), name
        assert lam == chain[0] == ref_lam
        assert np.array_equal(vec, chain[1]) and np.array_equal(vec, ref_vec)
        assert np.array_equal(force, force_chain) and np.array_equal(force, ref_force)
        nu = vec


def test_cached_force_is_used_only_for_its_eigenpair_and_potential() -> None:
    """Another vector, lambda2 or potential gets a freshly computed force."""
    world = World(dim=3, bounds_m=np.array([[0.0, 0, 0], [200.0, 200.0, 10.0]]))
    q = safe_team(world, 30, PARAMS, np.random.default_rng(3), margin_m=5.0, height_m=(1.0, 8.0))
    nu = compute_weights(q, PARAMS, None).fiedler()[1]
    with jit.using(True):
        g = compute_weights(q, PARAMS, None, guess=nu, with_force=True)
        lam, vec = g.fiedler(guess=nu)
        other = replace(PARAMS, potential_gain=2.0 * PARAMS.potential_gain)
        assert exact_force(g, lam, vec, PARAMS) is g._eigen[5]
        assert exact_force(g, lam, vec.copy(), PARAMS) is not g._eigen[5]
        assert exact_force(g, lam * 0.5, vec, PARAMS) is not g._eigen[5]
        doubled = exact_force(g, lam, vec, other)
    assert np.allclose(doubled, 2.0 * g._eigen[5], rtol=1e-12, atol=0.0)
