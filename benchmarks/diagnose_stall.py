"""Why a ``multi_target`` prime traveler stalls: the team's state at one instant of a run.

Re-runs a run folder's ``scenario.yaml`` (bit for bit; the positions are checked against
the folder's ``robots.parquet``) up to ``--at-s`` and prints, for the prime traveler:
where it is, its distance and remaining path to its target, its connectivity force
``f_lambda`` against its traveling force, and its links; for the team: every robot's hop
count from the prime, role and ``|f_lambda|``, every link's length, weight ``W``, pair
factor and line-of-sight clearance, the cycles of the weighted graph and lambda2 without
each cycle link (LAPACK), and the reach: the A* path length (the planner's grid and
inflation) from each robot to the prime's target against its hop count times ``Rs``.

Usage::

    python benchmarks/diagnose_stall.py RUN_FOLDER --at-s 900

A folder that is not a ``multi_target`` run, or a time outside the run, is a one-line
error (exit code 2). ``tests/test_diagnose_stall.py`` runs it on a short town run.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import networkx as nx
import numpy as np
import pyarrow.parquet as pq

from tether.config import load_scenario
from tether.continuous.connectivity.gradient import exact_force
from tether.continuous.exploration.motion import traveling_forces
from tether.continuous.exploration.roles import PRIME, ROLE_NAMES
from tether.graph.fiedler import fiedler
from tether.paths.astar import plan_path
from tether.runner import build
from tether.sim import StepContext


def replay(run: Path, steps: int) -> tuple:
    """The run's world, strategy and team state after ``steps`` control periods."""
    built = build(load_scenario(run / "scenario.yaml"))
    world, sensor, strategy, rng = built.world, built.sensor, built.strategy, built.rng
    state = built.initial.copy()
    strategy.reset(world, state, rng)
    obs = strategy.sense(state, world, sensor, rng)
    dt = float(load_scenario(run / "scenario.yaml").sim.dt_s)
    for step in range(steps):
        state = strategy.step(StepContext(step, step * dt, dt, world, state, obs, rng))
        strategy.drain_events()
        obs = strategy.sense(state, world, sensor, rng)
    return world, strategy, state


def recorded_positions(run: Path, step: int) -> np.ndarray | None:
    """The positions ``robots.parquet`` holds for ``step`` (``None``: not recorded)."""
    t = pq.read_table(run / "robots.parquet").to_pydict()
    sel = np.asarray(t["step"]) == step
    if not sel.any():
        return None
    return np.column_stack([np.asarray(t[c])[sel] for c in ("x_m", "y_m", "z_m")])


def path_length_m(world, planner, a: np.ndarray, b: np.ndarray) -> float:  # noqa: ANN001
    """A* waypoint length from ``a`` to ``b`` on the planner's grid (``inf``: no path)."""
    wp = plan_path(world, a, b, cell_m=planner.r_grid_m, inflate_m=planner.inflate_m,
                   planning=planner._planning)  # fmt: skip
    return np.inf if wp is None else float(np.linalg.norm(np.diff(wp, axis=0), axis=1).sum())


def inside_polygon(xy: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """Which ``(m, 2)`` points lie inside the closed ``(k, 2)`` polygon (even-odd rule)."""
    inside = np.zeros(len(xy), dtype=bool)
    for a, b in zip(poly, np.roll(poly, -1, axis=0), strict=True):
        crosses = (a[1] > xy[:, 1]) != (b[1] > xy[:, 1])
        with np.errstate(divide="ignore", invalid="ignore"):
            x_cross = a[0] + (xy[:, 1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1])
        inside ^= crosses & (xy[:, 0] < x_cross)
    return inside


def highest_obstacle_inside(world, poly: np.ndarray, step_m: float = 0.5) -> float:  # noqa: ANN001
    """Highest occupied height (m, to ``step_m / 2``) inside the ``(k, 2)`` polygon."""
    lo, hi = world.bounds_m
    xs = np.arange(lo[0], hi[0], step_m) + step_m / 2
    ys = np.arange(lo[1], hi[1], step_m) + step_m / 2
    xy = np.array(np.meshgrid(xs, ys)).reshape(2, -1).T
    xy = xy[inside_polygon(xy, poly)]
    for z in np.arange(hi[2] - step_m / 2, lo[2], -step_m):
        pts = np.column_stack([xy, np.full(len(xy), z)])
        if len(pts) and not world.points_free(pts).all():
            return float(z)
    return float(lo[2])


def report(world, strategy, state) -> None:  # noqa: ANN001
    """Print the prime's forces, links, the graph's cycles and the reach (see module doc)."""
    p, pl = strategy.params, strategy.planner
    q, v = state.positions, state.velocities
    graph, lam, nu = strategy._current[1]
    f_lambda = exact_force(graph, lam, nu, strategy.conn)
    f_travel = traveling_forces(q, v, f_lambda, pl, strategy.consensus.estimate, p)
    primes = np.flatnonzero(pl.role == PRIME)
    if not len(primes) or pl.target[primes[0]] is None:
        print("no prime traveler with a target at this instant")
        return
    pr = int(primes[0])
    target = pl.target[pr].position_m
    off_path, remaining = pl.on_path(q)
    pairs, w = graph.active()
    g = nx.Graph()
    g.add_nodes_from(range(len(q)))
    g.add_weighted_edges_from(
        (int(i), int(j), float(x)) for (i, j), x in zip(pairs, w, strict=True)
    )
    hops = nx.single_source_shortest_path_length(g, pr)
    print(f"lambda2 (weighted) {lam:.4g}; prime {pr} at {np.round(q[pr], 2).tolist()}, "
          f"|v| {np.linalg.norm(v[pr]):.3f} m/s")  # fmt: skip
    print(
        f"  target {np.round(target, 2).tolist()}: {np.linalg.norm(q[pr] - target):.2f} m "
        f"straight, remaining path {remaining[pr]:.2f} m, {off_path[pr]:.2f} m off its path"
    )
    lo, hi = world.bounds_m
    edge = min((target - lo).min(), (hi - target).min())
    print(f"  target's distance to the world's box {edge:.2f} m (box margin Ro {p.ro_m} m, "
          f"planning inflation {pl.inflate_m} m)")  # fmt: skip
    fl, ft = f_lambda[pr], f_travel[pr]
    print(f"  f_lambda {np.round(fl, 2).tolist()} (|{np.linalg.norm(fl):.2f}| N), f_travel "
          f"{np.round(ft, 2).tolist()} (|{np.linalg.norm(ft):.2f}| N, cap "
          f"{p.max_travel_force_n} N)")  # fmt: skip
    print(f"  help request: {strategy._depth.depth} hops, helpers {strategy._helpers.tolist()}")
    print("links (hop of each end, length, W, pair factor, line-of-sight clearance):")
    links = zip(graph.pairs, graph.weights, graph.pair_factor, graph.clearance_m, strict=True)
    for (i, j), x, pf, cl in links:
        if x > 0:
            d = np.linalg.norm(q[i] - q[j])
            print(f"  {i:2d}-{j:2d} hops {hops.get(int(i))}/{hops.get(int(j))} d {d:.2f} m "
                  f"W {x:.3f} P {pf:.3f} clearance {cl:.2f} m")  # fmt: skip
    print("robots by hop (role, position, |f_lambda|, A* to the target, per hop):")
    for i in sorted(range(len(q)), key=lambda k: (hops.get(k, 99), k)):
        h = hops.get(i)
        reach = path_length_m(world, pl, q[i], target)
        per = reach / h if h else reach
        print(f"  {i:2d} hop {h} {ROLE_NAMES[pl.role[i]]:9s} {np.round(q[i], 1).tolist()} "
              f"|f_lambda| {np.linalg.norm(f_lambda[i]):6.2f} N  A* {reach:5.1f} m, "
              f"{per:5.2f} m per hop (Rs {p.rs_m} m)")  # fmt: skip
    for cycle in nx.cycle_basis(g):
        top = highest_obstacle_inside(world, q[cycle, :2])
        print(f"cycle of {len(cycle)} robots: {cycle}; highest obstacle inside it {top:.2f} m, "
              f"robots fly up to {world.bounds_m[1][2] - p.ro_m:.2f} m")  # fmt: skip
        on = set(cycle)
        for k, (i, j) in enumerate(pairs):
            if int(i) in on and int(j) in on:
                keep = np.arange(len(pairs)) != k
                l2 = fiedler(len(q), pairs[keep], w[keep], method="lapack")[0]
                print(f"  without {i}-{j} (W {w[k]:.3f}): lambda2 {l2:.5f}")


def fail(message: str) -> None:
    """One line on stderr, exit code 2 (bad input, never a traceback)."""
    print(f"diagnose_stall: {message}", file=sys.stderr)
    raise SystemExit(2)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", type=Path, help="a run folder of a multi_target scenario")
    ap.add_argument("--at-s", type=float, required=True, help="simulated time to look at")
    args = ap.parse_args(argv)
    scenario = args.run / "scenario.yaml"
    if not scenario.is_file() or not (args.run / "robots.parquet").is_file():
        fail(f"{args.run}: not a run folder (no scenario.yaml and robots.parquet); "
                 "give a folder that `tether run` wrote")  # fmt: skip
    sc = load_scenario(scenario)
    if sc.strategy.name != "multi_target":
        fail(f"{args.run}: a {sc.strategy.name!r} run; this tool looks at multi_target runs")
    dt = float(sc.sim.dt_s)
    steps = round(args.at_s / dt)
    recorded = pq.read_table(args.run / "robots.parquet", columns=["step"]).column(0)
    last = int(max(recorded.to_pylist(), default=0))
    if not 0 <= steps <= last:
        fail(f"--at-s {args.at_s:g}: the run covers 0 to {last * dt:g} s; choose a time "
                 "in it")  # fmt: skip
    world, strategy, state = replay(args.run, steps)
    rec = recorded_positions(args.run, steps)
    if rec is not None:
        print(f"replayed {steps} steps; largest deviation from robots.parquet "
              f"{np.abs(state.positions - rec).max():.3g} m")  # fmt: skip
    report(world, strategy, state)


if __name__ == "__main__":
    main()
