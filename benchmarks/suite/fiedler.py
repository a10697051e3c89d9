"""The small certified Fiedler solver against LAPACK ``dsyevr``.

Every integrator sub-step of ``connectivity`` and ``multi_target`` needs the second
eigenpair of a team's weighted Laplacian. With ``fiedler_method: auto`` (the default) it
comes from :func:`tether.graph.small.small_fiedler` (compiled), warm-started from the
previous sub-step's vector and certified (inertia + Temple), falling back to ``dsyevr``
when it cannot certify. Peer: ``scipy.linalg.eigh(L, subset_by_index=[1, 1],
driver="evr")`` (LAPACK ``dsyevr``) on the same matrix, in turns.

Teams of 35, 100 and 400 robots in free 3-D space (the weights of ``connectivity``'s
defaults); the warm start is the Fiedler vector of the same team before every robot moved
by up to 2 cm (a sub-step's motion). The row also records the largest difference in
lambda2 between the two, relative to the largest degree.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg

from suite.core import Line, cpu_clock, paired, row

SIZES = (35, 100, 400)


def _problem(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(laplacian, pairs, guess)`` of a free-space team of ``n`` robots."""
    from tether.continuous.connectivity.placement import safe_team
    from tether.continuous.connectivity.strategy import ConnectivityStrategyParams
    from tether.continuous.connectivity.weights import compute_weights
    from tether.graph.structure import laplacian_dense
    from tether.world.clearance import ObstacleIndex
    from tether.world.world import World

    world = World(dim=3, bounds_m=np.array([[0.0, 0, 0], [200.0, 200.0, 10.0]]), name="free")
    params = ConnectivityStrategyParams().connectivity()
    rng = np.random.default_rng(n)
    q = safe_team(world, n, params, rng, margin_m=5.0, height_m=(1.0, 8.0))
    obstacles = ObstacleIndex.from_world(world)
    before = compute_weights(q, params, obstacles)
    _, guess = before.fiedler()
    moved = q + rng.uniform(-0.02, 0.02, q.shape)
    graph = compute_weights(moved, params, obstacles)
    lap = laplacian_dense(n, graph.pairs, graph.weights)
    return lap, graph.pairs, guess


@row("fiedler_small", "small certified Fiedler solver against LAPACK dsyevr")
def fiedler_small(quick: bool) -> dict:
    from tether import jit
    from tether.graph.fiedler import fiedler

    lines, details = [], []
    for n in SIZES[:1] if quick else SIZES:
        lap, pairs, guess = _problem(n)

        def ours(lap=lap, pairs=pairs, guess=guess, n=n) -> tuple[float, np.ndarray]:
            return fiedler(n, pairs, None, method="small", guess=guess, laplacian=lap)

        def peer(lap=lap) -> tuple[np.ndarray, np.ndarray]:
            return scipy.linalg.eigh(lap, subset_by_index=[1, 1], driver="evr")

        with jit.using(True):
            t0 = cpu_clock()
            lam, _ = ours()
            warm = cpu_clock() - t0
            peer()
            calls = max(3, 4000 // n) if not quick else 20
            rounds = 3 if quick else 9

            def batch_of(fn, calls=calls):  # noqa: ANN001, ANN202
                return lambda: [fn() for _ in range(calls)]

            times = paired({"ours": batch_of(ours), "peer": batch_of(peer)}, rounds)
        ref = float(peer()[0][0])
        scale = float(np.max(np.diagonal(lap)))
        rec = {
            "robots": n,
            "links": int(len(pairs)),
            "ours_s": times["ours"] / calls,
            "dsyevr_s": times["peer"] / calls,
            "lambda2": lam,
            "lambda2_difference_rel": abs(lam - ref) / scale,
        }
        details.append(rec)
        lines.append(
            Line(
                f"Fiedler pair of a {n}-robot team, small certified solver (warm start)",
                "us",
                1e6 * rec["ours_s"],
                goal="<= dsyevr",
                goal_value=1.0,
                goal_on="ratio",
                peer="LAPACK dsyevr (scipy eigh driver='evr')",
                peer_value=1e6 * rec["dsyevr_s"],
                warmup_s=warm,
                extra={"lambda2_difference_rel": rec["lambda2_difference_rel"]},
            )
        )
    return {"lines": lines, "details": {"teams": details}}
