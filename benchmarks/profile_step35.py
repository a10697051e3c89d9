"""Where the time of the 35-robot connectivity step goes (free 3-D space or the town).

The step of ``bench_continuous_step.bench`` (``compute_weights(guess=nu)``, the cached
eigenpair, ``exact_force``, the Euler update) and its parts, CPU time per call
(means of ``--repeat`` calls after one untimed call): the compiled work of each kernel
alone (timed by a loop inside numba, no Python or argument conversion) and each Python
call around it. ``TETHER_JIT=on``; warm numba's cache first
(``python -m tether.continuous.kernels``).

    python benchmarks/profile_step35.py [--world free|town] [--repeat 2000]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

os.environ["TETHER_JIT"] = "on"
for _var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import numpy as np  # noqa: E402
from numba import njit  # noqa: E402

sys.path.insert(0, str(Path(__file__).parent))
import bench_continuous_step as bcs  # noqa: E402
from tether.continuous.dynamics import semi_implicit_euler  # noqa: E402
from tether.continuous.gradient import exact_force  # noqa: E402
from tether.continuous.kernels import (  # noqa: E402
    evaluate_fiedler_free_kernel,
    evaluate_fiedler_kernel,
    evaluate_kernel,
    no_obstacles,
    pairs_in_range,
    weights_kernel,
)
from tether.continuous.strategy import ConnectivityStrategyParams  # noqa: E402
from tether.continuous.weights import compute_weights  # noqa: E402
from tether.graph import small  # noqa: E402
from tether.graph.fiedler import _syevr_lwork  # noqa: E402
from tether.graph.kernels import laplacian_dense_kernel  # noqa: E402
from tether.graph.small_kernels import small_fiedler_kernel  # noqa: E402
from tether.world.clearance import ObstacleIndex, einsum_order  # noqa: E402
from tether.world.scenes import make_scene  # noqa: E402
from tether.world.world import World  # noqa: E402


@njit
def _pairs_loop(reps, q, rs):  # noqa: ANN001, ANN202
    s = 0
    for _ in range(reps):
        s += len(pairs_in_range(q, rs))
    return s


@njit
def _weights_loop(reps, q, pairs, a, b, c, d, e, f):  # noqa: ANN001, ANN202, PLR0913
    s = 0.0
    z, z2 = np.zeros(0), np.zeros((0, q.shape[1]))
    for _ in range(reps):
        s += weights_kernel(q, pairs, False, z, z, z2, a, b, c, d, e, f)[0].sum()
    return s


@njit
def _laplacian_loop(reps, n, pairs, w):  # noqa: ANN001, ANN202
    s = 0.0
    for _ in range(reps):
        s += laplacian_dense_kernel(n, pairs, w)[0, 0]
    return s


@njit
def _small_loop(reps, lap, guess, settings):  # noqa: ANN001, ANN202
    s = 0.0
    a, b, c, d, e, f = settings
    for _ in range(reps):
        s += small_fiedler_kernel(lap, guess, a, b, c, d, e, f)[1]
    return s


def per_call(fn, repeat: int) -> float:  # noqa: ANN001
    fn()
    t0 = time.process_time()
    for _ in range(repeat):
        fn()
    return (time.process_time() - t0) / repeat * 1e6


def inner(loop, repeat: int, *args) -> float:  # noqa: ANN001, ANN002
    loop(1, *args)
    t0 = time.process_time()
    loop(repeat, *args)
    return (time.process_time() - t0) / repeat * 1e6


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--world", choices=["free", "town"], default="free")
    ap.add_argument("--repeat", type=int, default=2000)
    a = ap.parse_args()
    if a.world == "free":
        world = World(dim=3, bounds_m=np.array([[0.0, 0, 0], [200.0, 200.0, 10.0]]))
    else:
        world = make_scene("town", 0, size_m=(50.0, 70.0), resolution_m=0.25)
    p = ConnectivityStrategyParams()
    c = p.connectivity()
    q = bcs.team(world, 35, c, 35)
    v, ext = np.zeros_like(q), np.zeros_like(q)
    obs = ObstacleIndex.from_world(world)
    graph = compute_weights(q, c, obs)
    lam, nu = graph.fiedler()
    fused = compute_weights(q, c, obs, guess=nu, with_force=True)
    lam2, vec = fused.fiedler(guess=nu)
    radii = (c.rs_inner_m, c.rs_m, c.ro_m, c.ro_outer_m, c.rc_m, c.rc_outer_m)
    r = a.repeat

    def step() -> None:
        g = compute_weights(q, c, obs, guess=nu, with_force=True)
        l2, x = g.fiedler(guess=nu)
        f = exact_force(g, l2, x, c)
        semi_implicit_euler(q, v, f + ext, 1e-3, p.mass_kg, p.damping_ns_per_m)

    rows = {"step (as the probe)": per_call(step, r)}
    rows["compute_weights(guess=nu), Python + one kernel call"] = per_call(
        lambda: compute_weights(q, c, obs, guess=nu), r
    )
    if obs.tree is None:  # the kernel call alone and its parts (free space)
        st = no_obstacles(3)
        args = (q, *radii, False, *st[:4], 0.0, st[4], einsum_order())
        pot = (c.lambda2_min, c.lambda2_null, c.potential_gain)
        fused_args = (*args, nu, False, small.SETTINGS, *_syevr_lwork(35), pot, True)
        rows["  evaluate_fiedler_free_kernel call (+ eigenpair, force)"] = per_call(
            lambda: evaluate_fiedler_free_kernel(q, *radii, *fused_args[len(args) :]), r
        )
        rows["  the same through evaluate_fiedler_kernel (empty obstacle state)"] = per_call(
            lambda: evaluate_fiedler_kernel(*fused_args), r
        )
        rows["  evaluate_kernel call (no eigenpair)"] = per_call(
            lambda: evaluate_kernel(q, *radii, True, False, *st[:4], 0.0, st[4], einsum_order()),
            r,
        )
        rows["    compiled: pairs (595 tested)"] = inner(_pairs_loop, r, q, c.rs_m)
        rows["    compiled: weights"] = inner(_weights_loop, r, q, graph.pairs, *radii)
        rows["    compiled: Laplacian"] = inner(_laplacian_loop, r, 35, graph.pairs, graph.weights)
        rows["    compiled: small Fiedler solver"] = inner(
            _small_loop, r, fused._laplacian, nu, small.SETTINGS
        )
    rows["fiedler(guess=nu), eigenpair cached"] = per_call(lambda: fused.fiedler(guess=nu), r)
    rows["fiedler(guess=nu), no cache (small solver)"] = per_call(
        lambda: graph.fiedler(guess=nu), r
    )
    rows["exact_force"] = per_call(lambda: exact_force(fused, lam2, vec, c), r)
    rows["semi_implicit_euler (compiled with the kernels on)"] = per_call(
        lambda: semi_implicit_euler(q, v, q + ext, 1e-3, p.mass_kg, p.damping_ns_per_m), r
    )
    print(f"{a.world}, 35 robots, {len(graph.pairs)} links, load {os.getloadavg()[0]:.1f}")
    for name, us in rows.items():
        print(f"{name:55s} {us:7.1f} us")


if __name__ == "__main__":
    main()
