"""``build(scenario, seed)`` builds the trial ``tether run --seed`` runs, for every strategy.

A strategy may draw from ``scenario.seed`` as well as from the run's generator (the
targets of ``multi_target``: their configuration is the run seed). ``build`` with a seed
must give both the same seed, as ``tether run --seed`` does; a library caller (a
benchmark, an environment, a sweep check) would otherwise get the targets of the
scenario's own seed with the team of another.
"""

from __future__ import annotations

import numpy as np
import pyarrow.parquet as pq
import pytest

from tether.config import builtin_scenarios, load_scenario
from tether.plugins import load_builtins
from tether.registry import STRATEGIES
from tether.runner import build, run
from tether.sim import simulate

load_builtins()
SEED = 3
STEPS = 10  # a multiple of every built-in's record_every: the last step is recorded


def _builtin(strategy: str) -> str:
    return next(s for s in builtin_scenarios() if load_scenario(s).strategy.name == strategy)


@pytest.mark.parametrize("strategy", STRATEGIES.names())
def test_build_with_a_seed_is_the_run_of_that_seed(strategy, tmp_path, skip_without_shared_map):
    name = _builtin(strategy)
    sc = load_scenario(name)
    skip_without_shared_map(sc)
    sc.sim.max_steps = STEPS
    assert sc.seed != SEED
    out = run(sc, out_dir=tmp_path / "run", seed=SEED, figures=False)
    assert out.summary["seed"] == SEED

    built = build(sc, SEED)
    assert built.scenario.seed == SEED
    res = simulate(built.world, built.sensor, built.strategy, built.initial,
                   dt_s=sc.sim.dt_s, max_steps=STEPS, rng=built.rng,
                   collision_distance_m=sc.sim.collision_distance_m)  # fmt: skip
    t = pq.read_table(tmp_path / "run" / "robots.parquet").to_pydict()
    last = max(t["step"])
    rows = [i for i, s in enumerate(t["step"]) if s == last]
    recorded = np.array([[t[c][i] for c in ("x_m", "y_m", "z_m") if c in t] for i in rows])
    order = np.argsort([t["robot"][i] for i in rows])
    assert res.steps == out.summary["steps"] == last
    np.testing.assert_array_equal(res.final_state.positions, recorded[order])
    assert sc.seed != SEED  # the caller's scenario is left as it was
