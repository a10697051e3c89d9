"""Random team placements that start inside the connectivity strategy's safe set.

The connectivity force keeps ``lambda2 > lambda2_min`` only if it holds at the
start (App. A). :func:`safe_team` grows a team one robot at a time, each new
robot within ``[R'c, R's]`` of a random earlier robot (weight 1 with it),
farther than ``R'c`` from all others and ``R'o`` from every obstacle point, so
the initial weighted graph is connected.
"""

from __future__ import annotations

import numpy as np

from tether.continuous.connectivity.params import ConnectivityParams
from tether.continuous.connectivity.weights import compute_weights
from tether.world.clearance import ObstacleIndex
from tether.world.world import World


def safe_team(
    world: World,
    n: int,
    params: ConnectivityParams,
    rng: np.random.Generator,
    *,
    obstacles: ObstacleIndex | None = None,
    margin_m: float = 1.0,
    height_m: tuple[float, float] | None = None,
    center_m: list[float] | np.ndarray | None = None,
    box_margin_m: float = 0.0,
    max_tries: int = 50,
) -> np.ndarray:
    """``(n, dim)`` positions with ``lambda2 > lambda2_min`` in ``G_lambda``.

    Parameters
    ----------
    margin_m
        Keep the first robot this far inside the world's bounds.
    height_m
        For 3-D worlds, the range of heights of the first robot.
    center_m
        Where the first robot is (default: uniform in the bounds less ``margin_m``).
    box_margin_m
        Every robot at least this far inside the bounds (floor and ceiling in 3-D).
    """
    obstacles = obstacles or ObstacleIndex.shared(world)
    dim = world.dim
    lo, hi = (
        world.bounds_m if world.bounds_m is not None else (-np.full(dim, 10.0), np.full(dim, 10.0))
    )
    if center_m is not None:
        _check_center(world, np.asarray(center_m, dtype=float), params, obstacles)
    if world.bounds_m is not None:
        _check_room(n, dim, lo + box_margin_m, hi - box_margin_m, params.rc_outer_m)
    checks, most = 0, 0  # pair distances computed; the most robots placed in one try
    for _ in range(max_tries):
        if checks >= MAX_PAIR_CHECKS:
            break  # the work bound: a team this large that keeps jamming would run for hours
        if center_m is not None:
            start = np.asarray(center_m, dtype=float).copy()
        else:
            inset = np.minimum(margin_m, 0.5 * (hi - lo))  # a thin box keeps its middle
            start = rng.uniform(lo + inset, hi - inset)
        if center_m is None and dim == 3 and height_m is not None:
            start[2] = rng.uniform(*height_m)
        pts = np.empty((n, dim))  # the robots placed so far: pts[:count]
        pts[0], count = start, 1
        for _ in range(200 * n):
            if count == n:
                break
            checks += count
            anchor = pts[rng.integers(count)]
            direction = rng.normal(size=dim)
            direction /= np.linalg.norm(direction)
            cand = anchor + direction * rng.uniform(params.rc_outer_m, params.rs_inner_m)
            if np.min(np.linalg.norm(pts[:count] - cand, axis=1)) <= params.rc_outer_m:
                continue
            if not world.in_bounds(cand[None])[0]:
                continue
            if (
                box_margin_m > 0
                and world.bounds_m is not None
                and not (np.all(cand >= lo + box_margin_m) and np.all(cand <= hi - box_margin_m))
            ):
                continue
            if obstacles.tree is not None and obstacles.tree.query(cand)[0] <= params.ro_outer_m:
                continue
            if not world.points_free(cand[None])[0]:  # inside a thick obstacle, far from its faces
                continue
            pts[count] = cand
            count += 1
        most = max(most, count)
        if count < n:
            continue
        if not world.points_free(pts[0][None])[0]:
            continue
        q = pts
        if obstacles.tree is not None and obstacles.tree.query(q[0])[0] <= params.ro_outer_m:
            continue
        lam, _ = compute_weights(q, params, obstacles).fiedler()
        if lam > params.lambda2_min:
            return q
    if checks >= MAX_PAIR_CHECKS and most < n:
        raise ValueError(
            f"could not place {n} robots at least R'c = {params.rc_outer_m:g} m apart: the "
            f"world filled up after {most} in every try the placement's work bound allows; "
            "use fewer robots"
        )
    where = "around center_m" if center_m is not None else "at random starts"
    raise ValueError(
        f"could not place {n} robots with a connected weighted graph {where} in {max_tries} "
        f"tries (at most {most} fitted, each within R's = {params.rs_inner_m:g} m of another "
        f"and R'o = {params.ro_outer_m:g} m clear of obstacles); start in a larger free "
        "space (center_m) or use fewer robots"
    )


def _check_center(
    world: World, center: np.ndarray, params: ConnectivityParams, obstacles: ObstacleIndex
) -> None:
    """``center_m`` must be a point of the world's free space, clear of obstacles by R'o."""
    if center.shape != (world.dim,) or not np.isfinite(center).all():
        raise ValueError(f"center_m: must be {world.dim} finite numbers (got {center.tolist()})")
    if not world.in_bounds(center[None])[0]:
        raise ValueError(
            f"center_m: {center.tolist()} is outside the world's bounds "
            f"{np.round(world.bounds_m, 3).tolist()}; move the start inside them"
        )
    if not world.points_free(center[None])[0]:
        raise ValueError(
            f"center_m: {center.tolist()} is inside an obstacle; move the start into free space"
        )
    if obstacles.tree is not None:
        gap = float(obstacles.tree.query(center)[0])
        if gap <= params.ro_outer_m:
            raise ValueError(
                f"center_m: {center.tolist()} is {gap:.2f} m from an obstacle, within R'o = "
                f"{params.ro_outer_m:g} m; move the start farther from walls"
            )


#: robot-to-candidate distances the placement may compute over all its tries (a second
#: or two): a team that fits places in far fewer (a 35-robot Fig. 9 office team needs up
#: to 15 tries from its fixed start, about 1e5 each), a team that keeps filling its world
#: before it is complete stops here instead of running for hours
MAX_PAIR_CHECKS = 100_000_000
#: the densest packing of equal balls (Kepler) and of equal discs
_PACKING = {2: np.pi / (2 * np.sqrt(3)), 3: np.pi / (3 * np.sqrt(2))}


def _check_room(n: int, dim: int, lo: np.ndarray, hi: np.ndarray, separation_m: float) -> None:
    """Refuse a team that cannot fit in the box ``[lo, hi]`` with robots ``separation_m``
    apart, even packed densest (balls of radius ``separation_m / 2``)."""
    if dim not in _PACKING or n < 2:
        return
    r = 0.5 * separation_m
    room = float(np.prod(np.maximum(hi - lo, 0.0) + 2 * r))
    ball = np.pi * r**2 if dim == 2 else 4.0 / 3.0 * np.pi * r**3
    most = int(_PACKING[dim] * room / ball)
    if n > most:
        raise ValueError(
            f"{n} robots do not fit in the world at least R'c = {separation_m:g} m apart "
            f"(at most about {most} would, packed densest); use fewer robots"
        )
