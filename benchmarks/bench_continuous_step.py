"""Time one control step of strategy ``connectivity``: weights, eigenpair, gradient, update.

For N = 10, 35, 100, 1000 robots (and 10,000 in free space, on a jittered
3 m lattice, since the random-tree placement is quadratic in N), in free 3-D
space and in the town scene, with the exact eigensolver (full ``eigh`` up to
16 robots, the second eigenpair only up to 400, above the certified
warm-started iteration from the previous Fiedler vector, keeping its sparse
factorization between steps in a :class:`tether.graph.WarmState` as a run does,
falling back to sparse shift-invert Lanczos; ``eigen_cold_s`` times the solver
without a warm start, ``eigen_fresh_s`` with a warm start but a new
factorization each call, as when the graph changed more than its spectral gap
since the last one; ``factorizations`` counts the step's) and with the
decentralized estimator (``rounds`` communication rounds per step; on perfect
links computed as Laplacian products, with 10 % loss through the message
layer's mailboxes, ``estimator_loss10``, up to 100 robots). A "step" is one
integrator sub-step:
``compute_weights`` + eigenpair (or estimator rounds) + ``connectivity_force``
+ one semi-implicit Euler update. The safeguard's check of the candidate
configuration is the next step's weights + eigenpair, so it is included.

Usage::

    python benchmarks/bench_continuous_step.py [--quick] [--out PATH]

Writes ``benchmarks/results/continuous_step.json`` (or ``--out``).
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import time
from pathlib import Path

# One BLAS thread: for the tiny matrices of a team, OpenBLAS threading makes a 35 x 35
# eigh cost about 16 ms instead of 0.12 ms on a 2-core machine (measured).
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402

from tether.comm import CommParams  # noqa: E402
from tether.continuous.dynamics import semi_implicit_euler  # noqa: E402
from tether.continuous.estimation import FiedlerEstimator  # noqa: E402
from tether.continuous.gradient import connectivity_force, exact_force, messages
from tether.continuous.placement import safe_team  # noqa: E402
from tether.continuous.strategy import ConnectivityStrategyParams  # noqa: E402
from tether.continuous.weights import compute_weights
from tether.graph import WarmState
from tether.runfolder import machine  # noqa: E402
from tether.world.clearance import ObstacleIndex
from tether.world.scenes import make_scene  # noqa: E402
from tether.world.world import World  # noqa: E402

OUT = Path(__file__).parent / "results" / "continuous_step.json"


def timed(fn, repeat: int) -> float:  # noqa: ANN001
    """Median wall time of ``fn()`` in seconds."""
    fn()
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def team(world: World, n: int, params, seed: int) -> np.ndarray:  # noqa: ANN001
    rng = np.random.default_rng(seed)
    if n >= 10_000:  # 66 x 51 x 3 lattice, 3 m apart (inside R's, outside R'c), jittered
        cells = np.argwhere(np.ones((66, 51, 3), dtype=bool))[:n]
        return world.bounds_m[0] + [1.5, 1.5, 1.0] + 3.0 * cells + rng.uniform(-0.4, 0.4, (n, 3))
    return safe_team(world, n, params, rng, margin_m=5.0, height_m=(1.0, 8.0))


def bench(world: World, n: int, solver: str, rounds: int, repeat: int, loss: float = 0.0) -> dict:
    p = ConnectivityStrategyParams()
    c = p.connectivity()
    q = team(world, n, c, n)
    v = np.zeros_like(q)
    obs = ObstacleIndex.from_world(world)
    ext = np.zeros_like(q)
    graph = compute_weights(q, c, obs)
    lam, nu = graph.fiedler()
    est = None
    if solver.startswith("estimator"):
        comm = CommParams(loss_probability=loss)
        est = FiedlerEstimator.create(n, np.random.default_rng(0), comm=comm)
        est.update(graph, 200)

    def weights() -> None:
        compute_weights(q, c, obs)

    states = {"eigen": WarmState(), "step": WarmState()}  # as a run keeps one
    primer = WarmState()  # first calls untimed: the factoring path, then the reusing one
    for _ in range(2):  # (its first call loads numba's cached kernels, ~10 ms once)
        graph.fiedler(guess=nu, state=primer)

    def eigen() -> None:
        graph.fiedler(guess=nu, state=states["eigen"])

    def eigen_fresh() -> None:  # a new factorization each call (a graph that moved a lot)
        graph.fiedler(guess=nu)

    def eigen_cold() -> None:
        graph.fiedler()

    def estimator() -> None:
        est.update(graph, rounds)

    def gradient() -> None:
        connectivity_force(graph, lam, messages(graph, nu), c)

    def step() -> None:
        g = compute_weights(
            q, c, obs, guess=nu if est is None else None, with_force=est is None
        )  # as the strategy
        if est is None:
            l2, vec = g.fiedler(guess=nu, state=states["step"])
            f = exact_force(g, l2, vec, c)  # as the strategy's exact path
        else:
            est.update(g, rounds)
            l2, vec = est.lambda2, est.vector
            f = connectivity_force(g, l2, messages(g, vec), c)
        semi_implicit_euler(q, v, f + ext, 1e-3, p.mass_kg, p.damping_ns_per_m)

    row = {
        "world": world.name,
        "n_robots": n,
        "solver": solver,
        "estimator_rounds_per_step": rounds if est is not None else 0,
        "links": int(len(graph.pairs)),
        "active_links": int((graph.weights > 0).sum()),
        "lambda2": lam,
        "weights_s": timed(weights, repeat),
        "gradient_s": timed(gradient, repeat),
        "step_s": timed(step, repeat),
    }
    row["eigen_s" if est is None else "estimator_s"] = timed(
        eigen if est is None else estimator, repeat
    )
    if est is None:
        row["eigen_cold_s"] = timed(eigen_cold, repeat)
        row["eigen_fresh_s"] = timed(eigen_fresh, repeat)
        row["factorizations"] = states["step"].factorizations
    return row


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="fewer repeats, no N >= 1000")
    parser.add_argument("--only", help="comma-separated world names (default: all)")
    parser.add_argument("--out", type=Path, default=OUT, help=f"JSON file (default: {OUT})")
    args = parser.parse_args()
    out = args.out
    sizes = [10, 35, 100] if args.quick else [10, 35, 100, 1000, 10_000]
    worlds = {
        "free": World(dim=3, bounds_m=np.array([[0.0, 0, 0], [200.0, 200.0, 10.0]]), name="free"),
        "town": make_scene("town", 0, size_m=(50.0, 70.0), resolution_m=0.25),
        # the same town with obstacle points thinned to one per 0.5 m (scene option)
        "town_0.5m": make_scene(
            "town", 0, size_m=(50.0, 70.0), resolution_m=0.25, point_spacing_m=0.5
        ),
    }
    if args.only:
        worlds = {k: w for k, w in worlds.items() if k in args.only.split(",")}
    rows = []
    for name, world in worlds.items():
        world.name = name
        for n in sizes:
            if name.startswith("town") and n > 100:
                continue  # 1,000 robots do not fit in the town's streets with these radii
            for solver, rounds, loss in (
                ("exact", 0, 0.0),
                ("estimator", 20, 0.0),
                ("estimator_loss10", 20, 0.1),
            ):
                if loss and n > 100:
                    continue
                repeat = 3 if n >= 10_000 else 5 if n >= 1000 else (30 if args.quick else 200)
                row = bench(world, n, solver, rounds, repeat, loss)
                rows.append(row)
                print(
                    f"{name:9s} N={n:5d} {solver:16s} links={row['links']:6d} "
                    f"weights={row['weights_s'] * 1e6:9.1f}us "
                    f"eig/est={row.get('eigen_s', row.get('estimator_s')) * 1e6:9.1f}us "
                    f"gradient={row['gradient_s'] * 1e6:8.1f}us step={row['step_s'] * 1e6:9.1f}us"
                )
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(
        json.dumps(
            {
                "benchmark": "continuous_step",
                "date": dt.datetime.now(dt.timezone.utc).isoformat(),
                "machine": machine(),
                "units": "seconds (median wall time)",
                "results": rows,
            },
            indent=2,
        )
    )
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
