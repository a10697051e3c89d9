"""Geodesic searches on the Cluttered map: scipy's Dijkstra against the compiled one.

    python benchmarks/bench_geodesic.py

12 random sources on the coarse grid (factor 3) of ``../shared/maps/grass.png``'s free
space; CPU time per search of the original call (``dijkstra(directed=False)`` with
predecessors), of :meth:`CoarseGrid.geodesics` with the kernels on, and of distances
only; best of 3 (the compiled call warmed first). Then how often the kernel cannot
tell scipy's predecessor (flagged ties) and how many of 600 random paths cross one.
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from PIL import Image
from scipy.sparse.csgraph import dijkstra

from tether import jit
from tether.paths.geodesic import CoarseGrid, _trace

MAP = Path(__file__).resolve().parents[1] / ".." / "shared" / "maps" / "grass.png"


def main() -> None:
    image = np.asarray(Image.open(MAP).convert("L"))[::-1].T
    grid = CoarseGrid(image > 0, 3)
    src = np.random.default_rng(0).choice(grid.n_nodes, 12, replace=False)
    best = {"scipy": np.inf, "geodesics": np.inf, "distances": np.inf}
    with jit.using(True):
        grid.geodesics(src[:1])
        for _ in range(3):
            for name, call in (
                (
                    "scipy",
                    lambda: dijkstra(
                        grid.graph, directed=False, indices=src, return_predecessors=True
                    ),
                ),  # fmt: skip
                ("geodesics", lambda: grid.geodesics(src)),
                ("distances", lambda: grid.distances(src)),
            ):
                t0 = time.process_time()
                call()
                best[name] = min(best[name], (time.process_time() - t0) / len(src))
    print(f"{grid.n_nodes} nodes; ms per search: "
          + ", ".join(f"{k} {1e3 * v:.1f}" for k, v in best.items()))  # fmt: skip
    with jit.using(True):
        geo = grid.geodesics(src)
    rng = np.random.default_rng(1)
    crossed = 0
    for i in range(len(src)):
        for t in rng.choice(np.flatnonzero(np.isfinite(geo.dist[i])), 50):
            crossed += bool(geo.tie[i, _trace(geo.pred[i], int(t))].any())
    print(f"ties: {100 * geo.tie.mean():.2f} % of the nodes; {crossed} of 600 paths cross one")


if __name__ == "__main__":
    main()
