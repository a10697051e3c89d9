"""Initial team placements."""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

from tether.config import InitConfig
from tether.graph import is_connected, pairs_within
from tether.world.world import World


def default_center(world: World) -> np.ndarray:
    """Where a team is placed when ``team.init.center`` is not given."""
    if world.bounds_m is not None:
        return world.bounds_m.mean(axis=0)
    return np.zeros(world.dim)


def random_connected(
    n: int,
    world: World,
    rng: np.random.Generator,
    spacing_m: float,
    min_separation_m: float = 0.0,
    center: np.ndarray | None = None,
    max_tries: int = 30,
) -> np.ndarray:
    """``n`` robots grown from ``center``, each within ``spacing_m`` of a random earlier one.

    A new robot is drawn at distance ``spacing_m * U(0.3, 1)`` in a uniform
    direction from an *anchor*, a uniformly random robot placed earlier; it is
    kept if it is in free space, sees its anchor (clear segment) and is at least
    ``min_separation_m`` from every robot. The disc graph of radius
    ``spacing_m`` is therefore connected by construction.

    O(n log n), and the same process: candidates are drawn in batches, checked
    together against a k-d tree of the robots placed so far and accepted in
    order (a candidate within ``min_separation_m`` of an earlier accepted one of
    its batch is refused, as one at a time). A batch may add at most 1/32 of the
    team (one robot at a time while the team has fewer than 64), so anchors lag
    the team by at most 3 %; the statistics (spread, nearest-neighbour distance,
    degree) match the one-at-a-time process (tests/test_placement.py). An
    anchor around which ``max_tries`` candidates were refused is retired (its
    neighbourhood is full: this is what makes large teams fast, and it changes
    nothing for anchors with room). When every anchor is retired, the
    placement is refused with a ``ValueError``; the work is bounded by about
    ``n * (max_tries + 1)`` candidates.
    """
    dim = world.dim
    center = default_center(world) if center is None else np.asarray(center, dtype=float)
    if not np.isfinite(center).all():
        raise ValueError("center: must be finite")
    if not world.points_free(center[None])[0]:
        raise ValueError(
            f"center: {center.tolist()} is inside an obstacle or outside the world; "
            "move the team into free space"
        )
    if not (np.isfinite(spacing_m) and spacing_m > 0):
        raise ValueError(f"spacing_m: must be a positive finite number (got {spacing_m!r})")
    pos = np.empty((n, dim))
    pos[0] = center
    count = 1
    fails = np.zeros(n, dtype=np.int64)
    alive = np.zeros(n, dtype=bool)
    alive[0] = True
    tree, tree_count = None, 0
    rate = 1.0  # the share of candidates accepted lately
    reach = np.inf  # how many candidates the last batch could decide (conflict chains)
    while count < n:
        anchors_alive = np.flatnonzero(alive[:count])
        if len(anchors_alive) == 0:
            raise ValueError(
                f"could not place robot {count} of {n}: no free space is left within "
                f"spacing_m={spacing_m:g} of the team with robots min_separation_m="
                f"{min_separation_m:g} apart; lower n_robots or min_separation_m, raise "
                "spacing_m, or give the team more room"
            )
        limit = min(max(1, count // 32), n - count)  # robots this batch may add
        batch = int(min(max(1.0, 1.2 * limit / rate), 2 * reach, 4 * len(anchors_alive) + 16))
        anchors = anchors_alive[rng.integers(len(anchors_alive), size=batch)]
        direction = rng.normal(size=(batch, dim))
        norm = np.linalg.norm(direction, axis=1)
        direction /= np.where(norm > 0, norm, 1.0)[:, None]
        radius = spacing_m * rng.uniform(0.3, 1.0, size=batch)
        cand = pos[anchors] + radius[:, None] * direction
        ok = world.points_free(cand)
        if min_separation_m > 0 and ok.any():
            if tree_count != count:
                tree = cKDTree(pos[:count], balanced_tree=False, compact_nodes=False)
                tree_count = count
            idx = np.flatnonzero(ok)
            dist, _ = tree.query(cand[idx], k=1, distance_upper_bound=min_separation_m)
            ok[idx[dist < min_separation_m]] = False
        if ok.any():
            idx = np.flatnonzero(ok)
            ok[idx[~world.segments_clear(pos[anchors[idx]], cand[idx])]] = False
        tried, reach = batch, np.inf
        if min_separation_m > 0 and ok.sum() > 1:
            idx = np.flatnonzero(ok)
            pairs = cKDTree(cand[idx]).query_pairs(r=min_separation_m, output_type="ndarray")
            if len(pairs):
                keep, decided = _first_come(len(idx), pairs)
                ok[idx[~keep]] = False
                if decided < len(idx):  # from there on, candidates count as not tried
                    tried = reach = int(idx[decided])
                    ok[tried:] = False
        accepted = np.flatnonzero(ok)[:limit]
        if len(accepted) == limit:  # the candidates after the last accepted one: not tried
            tried = int(accepted[-1]) + 1
        refused = anchors[:tried][~ok[:tried]]
        np.add.at(fails, refused, 1)
        alive[refused] &= fails[refused] < max_tries
        pos[count : count + len(accepted)] = cand[accepted]
        alive[count : count + len(accepted)] = True
        count += len(accepted)
        rate = max(len(accepted), 0.5) / tried
    return pos


def _first_come(k: int, pairs: np.ndarray, rounds: int = 12) -> tuple[np.ndarray, int]:
    """Which of ``k`` candidates, taken in order, are kept when close pairs exclude each other.

    Candidate ``j`` is kept iff no kept candidate ``i < j`` is paired with it:
    what placing them one at a time gives. Resolved in vectorised rounds (a
    candidate is decided once every earlier partner is); after ``rounds``
    rounds the answer is exact for the first ``m`` candidates, ``m`` returned
    with the mask (the later ones count as not tried).
    """
    pairs = np.sort(np.asarray(pairs, dtype=np.intp), axis=1)
    first, second = pairs[:, 0], pairs[:, 1]
    state = np.zeros(k, dtype=np.int8)  # 0 undecided, 1 kept, -1 refused
    state[np.setdiff1d(np.arange(k), second)] = 1
    for _ in range(rounds):
        undecided = state == 0
        if not undecided.any():
            break
        blocked = np.zeros(k, dtype=bool)
        blocked[second[state[first] == 1]] = True
        waiting = np.zeros(k, dtype=bool)
        waiting[second[state[first] == 0]] = True
        state[undecided & blocked] = -1
        state[undecided & ~blocked & ~waiting] = 1
    open_ = np.flatnonzero(state == 0)
    return state == 1, int(open_[0]) if len(open_) else k


def uniform_connected(
    n: int,
    world: World,
    rng: np.random.Generator,
    extent_m: np.ndarray,
    range_m: float,
    min_separation_m: float = 0.0,
    center: np.ndarray | None = None,
    max_tries: int = 2000,
) -> np.ndarray:
    """``n`` robots uniform in a box, redrawn until connected within ``range_m``.

    At most ``max_tries`` draws, fewer for large teams (about 2 million robot
    positions in all), so that an impossible request is refused in seconds.
    """
    max_tries = uniform_tries(n, max_tries)
    center = default_center(world) if center is None else np.asarray(center, dtype=float)
    extent = np.broadcast_to(np.asarray(extent_m, dtype=float), (world.dim,))
    _check_box_fits(n, extent, range_m, min_separation_m)
    for _ in range(max_tries):
        pos = center + (rng.random((n, world.dim)) - 0.5) * extent
        if not world.points_free(pos).all():
            continue
        if min_separation_m > 0 and len(pairs_within(pos, min_separation_m)):
            continue
        if is_connected(n, pairs_within(pos, range_m)):
            return pos
    raise ValueError(
        f"no connected placement of {n} robots in a box of {extent.tolist()} m found in "
        f"{max_tries} draws; shrink extent_m or raise the sensing range"
    )


def uniform_tries(n: int, max_tries: int) -> int:
    """The draws :func:`uniform_connected` makes at most for ``n`` robots."""
    return int(min(max_tries, max(10, 2_000_000 // max(n, 1))))


MAX_EXPECTED_PAIRS = 50_000_000  # links of a uniform draw listed at once (~0.8 GB)


def _check_box_fits(n: int, extent: np.ndarray, range_m: float, separation_m: float) -> None:
    """Refuse, before any draw, a box that cannot hold ``n`` robots ``separation_m`` apart
    (discs of radius ``separation_m / 2`` centred in the box lie in the box grown by
    ``separation_m`` and cannot fill more than the densest packing, pi / sqrt(12) in 2-D,
    pi / sqrt(18) in 3-D), or whose draws would list more than ``MAX_EXPECTED_PAIRS``
    links within ``range_m`` (the expected count: each pair is in range with probability
    at most a ball's volume over the box's)."""
    dim = len(extent)
    ball = math.pi ** (dim / 2) / math.gamma(dim / 2 + 1)  # volume of the unit ball
    if separation_m > 0:
        density = {2: math.pi / math.sqrt(12), 3: math.pi / math.sqrt(18)}.get(dim, 1.0)
        fit = density * float(np.prod(extent + separation_m)) / (ball * (separation_m / 2) ** dim)
        if n > fit:
            raise ValueError(
                f"extent_m: {n:,} robots at least {separation_m:g} m apart do not fit in a "
                f"box of {extent.tolist()} m (at most {int(fit):,}); enlarge extent_m, lower "
                "min_separation_m or place fewer robots"
            )
    share = min(1.0, ball * min(range_m, 1e7) ** dim / max(float(np.prod(extent)), 1e-300))
    pairs = n * (n - 1) / 2 * share
    if pairs > MAX_EXPECTED_PAIRS:
        raise ValueError(
            f"extent_m: {n:,} robots in a box of {extent.tolist()} m would have about "
            f"{pairs:,.0f} links within {range_m:g} m (at most {MAX_EXPECTED_PAIRS:,}); "
            "enlarge extent_m or place fewer robots"
        )


def grid_positions(n: int, dim: int, spacing_m: float, center: np.ndarray) -> np.ndarray:
    """A square (2-D) or cubic (3-D) lattice of ``n`` points centred on ``center``."""
    side = int(np.ceil(n ** (1.0 / dim)))
    axes = [np.arange(side) * spacing_m] * dim
    pts = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, dim)[:n]
    return pts - pts.mean(axis=0) + center


def initial_positions(
    cfg: InitConfig, n: int, world: World, rng: np.random.Generator, range_m: float = np.inf
) -> np.ndarray:
    """Place the team as ``cfg`` says (see :class:`tether.config.InitConfig`)."""
    center = None if cfg.center is None else np.asarray(cfg.center, dtype=float)
    if center is not None and len(center) != world.dim:
        raise ValueError(
            f"center: must have {world.dim} coordinates for a {world.dim}-D world "
            f"(got {len(center)})"
        )
    if cfg.kind == "positions":
        if cfg.positions is None:
            raise ValueError("positions: kind 'positions' needs a 'positions' list")
        try:
            pos = np.asarray(cfg.positions, dtype=float)
        except ValueError:  # ragged
            pos = np.empty(0)
        if pos.ndim != 2 or pos.shape != (n, world.dim):
            raise ValueError(
                f"positions: must be n_robots = {n} points of {world.dim} coordinates "
                f"(got {len(cfg.positions)})"
            )
        return pos
    if cfg.kind == "grid":
        return grid_positions(
            n, world.dim, cfg.spacing_m, default_center(world) if center is None else center
        )
    if cfg.kind == "uniform":
        if cfg.extent_m is None or len(cfg.extent_m) not in (1, world.dim):
            raise ValueError(
                f"extent_m: kind 'uniform' needs extent_m with {world.dim} side lengths"
            )
        return uniform_connected(
            n, world, rng, np.asarray(cfg.extent_m), range_m, cfg.min_separation_m, center
        )
    return random_connected(n, world, rng, cfg.spacing_m, cfg.min_separation_m, center)
