"""How often a moving large team reuses the warm Fiedler solver's factorization.

The issue-14 step (``bench_continuous_step``) repeats one integrator sub-step of a team
at rest, where the Laplacian hardly changes and the kept factorization
(:class:`tether.graph.WarmState`) is reused every step. This script runs the
``connectivity`` strategy itself on the same team (the jittered lattice above 10,000
robots, ``safe_team`` below; free 3-D space, ``dt = 0.1 s``) for ``--steps`` control
steps, with robot 0 pulled towards a far goal (``goal``) or random forces on every
robot (``random``), and reports the CPU time per control step, the integrator's
sub-steps, and how many eigen-solves factored afresh or reused the kept factorization.
It also reports lambda2 and lambda3 of the first graph, whose gap the Laplacian's
change per step must stay below for a reuse (Weyl's inequality).

    python benchmarks/bench_warm_reuse.py [--n 1000] [--steps 20] [--dt 0.1] [--kinds goal random]

``PYTHONPATH=<other tree>/src`` runs another tree's strategy (counts then ``null``).

Prints one JSON line per kind (``time.process_time``).
"""

from __future__ import annotations

import argparse
import json
import os
import time

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
from scipy.sparse.linalg import eigsh  # noqa: E402

from tether.continuous.placement import safe_team  # noqa: E402
from tether.continuous.strategy import ConnectivityStrategy, ConnectivityStrategyParams  # noqa: E402
from tether.continuous.weights import compute_weights  # noqa: E402
from tether.graph import laplacian  # noqa: E402
from tether.sim import StepContext, TeamState  # noqa: E402
from tether.world.world import World  # noqa: E402

EXTERNAL = {
    "goal": {"kind": "goal", "robots": [0], "goals": [[190.0, 190.0, 4.0]],
             "gain_n_per_m": 1.0, "magnitude_n": 3.0},
    "random": {"kind": "random", "magnitude_n": 1.0, "hold_s": 1.0},
}  # fmt: skip


def team(world: World, n: int, params, seed: int) -> np.ndarray:  # noqa: ANN001
    """``bench_continuous_step.team`` (copied: this script also runs on trees without it)."""
    rng = np.random.default_rng(seed)
    if n >= 10_000:
        cells = np.argwhere(np.ones((66, 51, 3), dtype=bool))[:n]
        return world.bounds_m[0] + [1.5, 1.5, 1.0] + 3.0 * cells + rng.uniform(-0.4, 0.4, (n, 3))
    return safe_team(world, n, params, rng, margin_m=5.0, height_m=(1.0, 8.0))


def run(n: int, steps: int, kind: str, dt_s: float = 0.1) -> dict:
    """One run; its CPU time per control step and the solver's counts."""
    world = World(dim=3, bounds_m=np.array([[0.0, 0, 0], [200.0, 200.0, 10.0]]), name="free")
    params = ConnectivityStrategyParams(external=EXTERNAL[kind])
    q = team(world, n, params.connectivity(), n)
    graph = compute_weights(q, params.connectivity())
    vals = np.sort(eigsh(laplacian(n, graph.pairs, graph.weights).tocsc(), k=3, sigma=-1e-3)[0])
    strategy = ConnectivityStrategy(params)
    rng = np.random.default_rng(0)
    state = TeamState(q, np.zeros_like(q))
    strategy.reset(world, state, rng)
    t0 = time.process_time()
    for k in range(steps):
        state = strategy.step(StepContext(k, dt_s * k, dt_s, world, state, None, rng))
    cpu = time.process_time() - t0
    warm = getattr(strategy, "_warm", None)
    return {
        "n_robots": n,
        "kind": kind,
        "steps": steps,
        "dt_s": dt_s,
        "cpu_per_step_s": cpu / steps,
        "substeps": strategy._stats["substeps"],
        "factorizations": getattr(warm, "factorizations", None),
        "reuses": getattr(warm, "reuses", None),
        "lambda2": float(vals[1]),
        "lambda3": float(vals[2]),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=1000)
    parser.add_argument("--steps", type=int, default=20)
    parser.add_argument("--dt", type=float, default=0.1)
    parser.add_argument("--kinds", nargs="+", default=["goal", "random"], choices=EXTERNAL)
    args = parser.parse_args()
    for kind in args.kinds:
        print(json.dumps(run(args.n, args.steps, kind, args.dt)), flush=True)


if __name__ == "__main__":
    main()
