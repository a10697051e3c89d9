"""Where a large team's warm Fiedler solve spends its time (issue 14's 1,000 / 10,000 rows).

On ``bench_continuous_step``'s team (``bench_warm_reuse.team``; free 3-D space), CPU
time per call of the weights and their pair search, and of each part of a solve that
factors afresh -- the scipy Laplacian (as before branch ``big``), ``L - tau I`` from
the links, SuperLU's ``L D L'`` with its fill, one solve, one product ``L x`` -- and of
a solve that reuses a kept factorization (:class:`tether.graph.WarmState`): the links,
the bound on the change, the whole call. Also lambda2..lambda4 (``eigsh``), whose gap
decides how far a kept factorization reaches.

    python benchmarks/profile_warm_solver.py [--n 1000] [--repeat 5]

With ``PYTHONPATH=<older tree>/src`` it profiles that tree (without the reuse entries).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
from scipy.sparse import identity  # noqa: E402
from scipy.sparse.linalg import eigsh, splu  # noqa: E402

sys.path.insert(0, str(Path(__file__).parent))
from bench_warm_reuse import team  # noqa: E402
from tether.continuous.kernels import pairs_in_range  # noqa: E402
from tether.continuous.strategy import ConnectivityStrategyParams  # noqa: E402
from tether.continuous.weights import compute_weights  # noqa: E402
from tether.graph import laplacian  # noqa: E402
from tether.world.world import World  # noqa: E402

try:  # branch big's solver; on an older tree (PYTHONPATH=<tree>/src) only the rest
    from tether.graph import WarmState
    from tether.graph.links import Links, change_bound
except ImportError:
    WarmState = None


def cpu(fn, repeat: int) -> float:  # noqa: ANN001
    """Mean CPU time of ``fn()`` over ``repeat`` calls after one untimed call."""
    fn()
    t0 = time.process_time()
    for _ in range(repeat):
        fn()
    return (time.process_time() - t0) / repeat


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=1000)
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    n, rep = args.n, args.repeat
    world = World(dim=3, bounds_m=np.array([[0.0, 0, 0], [200.0, 200.0, 10.0]]), name="free")
    params = ConnectivityStrategyParams().connectivity()
    graph = compute_weights(team(world, n, params, n), params)
    pairs, w = graph.pairs, graph.weights
    lam, nu = graph.fiedler()
    q = np.ascontiguousarray(team(world, n, params, n))
    tau = 1.01 * lam
    shifted = (laplacian(n, pairs, w) - tau * identity(n)).tocsc()
    lu = splu(shifted, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
              options={"SymmetricMode": True})  # fmt: skip
    vals = np.sort(eigsh(laplacian(n, pairs, w).tocsc(), k=4, sigma=-1e-3)[0])
    out = {
        "n_robots": n,
        "links": len(pairs),
        "lambda2_4": vals[1:].tolist(),
        "factor_nnz_L": int(lu.L.nnz),
        "weights_s": cpu(lambda: compute_weights(q, params), rep),
        "pair_search_s": cpu(lambda: pairs_in_range(q, params.rs_m), rep),
        "scipy_laplacian_s": cpu(lambda: laplacian(n, pairs, w).tocsc(), rep),
        "superlu_s": cpu(
            lambda: splu(
                shifted,
                permc_spec="MMD_AT_PLUS_A",
                diag_pivot_thresh=0.0,
                options={"SymmetricMode": True},
            ),
            rep,
        ),  # fmt: skip
        "solve_s": cpu(lambda: lu.solve(nu), rep),
        "fresh_call_s": cpu(lambda: graph.fiedler(guess=nu), rep),
    }
    if WarmState is not None:
        links = Links.from_pairs(n, pairs, w)
        state = WarmState()
        graph.fiedler(guess=nu, state=state)
        out.update(
            links_shifted_s=cpu(lambda: links.shifted(tau), rep),
            product_s=cpu(lambda: links.product(nu), rep),
            links_s=cpu(lambda: Links.from_pairs(n, pairs, w), rep),
            change_bound_s=cpu(lambda: change_bound(state.links, links), rep),
            reuse_call_s=cpu(lambda: graph.fiedler(guess=nu, state=state), rep),
        )
    print(json.dumps(out))


if __name__ == "__main__":
    main()
