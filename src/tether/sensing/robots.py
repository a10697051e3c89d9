"""Who senses whom, and what they measure.

A robot ``i`` senses robot ``k`` when (a) ``||X_k - X_i|| <= range_m``,
(b) the straight line of sight between them is clear of obstacles, and (c) no
third robot's body (a disc/sphere of ``body_radius_m``) hides one from the
other. Sensing is mutual, so the sensed pairs form an undirected graph: the
*interaction graph* whose connectivity every strategy must keep.

Occlusion follows the non-communicating paper (Kerestecioglu & Cezayirli,
Fig. 3): robot ``j`` hides ``k`` from ``i`` when its body meets the segment
``i-k`` and ``j`` lies between them, i.e. closer to both ends than they are to
each other. With that definition an occluded pair is always joined through
the occluder by strictly shorter links, so occlusion never changes whether the
team is connected, only how many links it has (the paper's remark after
Theorem 1).

Measurements are relative positions in the observer's frame with bounded
errors (the paper's Fig. 1): radial error ``|e_r| <= radial_error_m`` and
angular error ``|e_theta| <= angular_error_rad``. ``noise="uniform"`` draws
both uniformly within their bounds; ``noise="bound"`` puts both exactly at a
bound with random sign (the worst case for the constraints).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cache
from types import ModuleType
from typing import Any, Literal

import numpy as np

from tether import jit
from tether.geometry import random_perpendicular, unit
from tether.graph import expand_rows, pairs_within
from tether.graph.structure import KERNEL_PAIRS_MAX_N
from tether.world.grid import OccupancyGrid
from tether.world.world import World

NoiseKind = Literal["none", "uniform", "bound"]

#: below this many robots the sensing kernels run only if numba is loaded already (or
#: TETHER_JIT=on): loading numba (about a second) would cost a short small-team run more
#: than the kernels save (as :data:`tether.silent.steering.KERNEL_MIN_ROBOTS`)
KERNEL_MIN_ROBOTS = 200


@cache
def _kernels() -> ModuleType:
    """:mod:`tether.sensing.robots_kernels`, imported on first use (it loads numba).

    Cached: an import statement run every step costs microseconds.
    """
    from tether.sensing import robots_kernels

    return robots_kernels


@cache
def _draws_kernels() -> ModuleType:
    """:mod:`tether.sensing.draws_kernels`, imported on first use."""
    from tether.sensing import draws_kernels

    return draws_kernels


def _use_kernel(n: int) -> bool:
    """Whether :func:`sense` runs :mod:`tether.sensing.robots_kernels` for ``n`` robots."""
    if n < 2 or not jit.enabled():
        return False
    return n >= KERNEL_MIN_ROBOTS or jit.warm() or jit.mode() == "on"


@dataclass(frozen=True)
class SensorModel:
    """Range, line of sight, occlusion by robot bodies and bounded noise."""

    range_m: float
    body_radius_m: float = 0.0
    occlusion: bool = True
    radial_error_m: float = 0.0
    angular_error_rad: float = 0.0
    noise: NoiseKind = "uniform"

    def __post_init__(self) -> None:
        for name in ("range_m", "body_radius_m", "radial_error_m", "angular_error_rad"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int | float | np.number):
                raise TypeError(f"{name} must be a number (got {type(value).__name__} {value!r})")
            if not np.isfinite(value):
                raise ValueError(f"{name} must be finite (got {value!r})")
        if not self.range_m > 0:
            raise ValueError(f"range_m must be > 0 (got {self.range_m!r})")
        if self.body_radius_m < 0 or self.radial_error_m < 0 or self.angular_error_rad < 0:
            raise ValueError("body radius and error bounds must be >= 0")
        if self.radial_error_m >= self.range_m:
            raise ValueError("radial_error_m must be smaller than range_m")
        if self.angular_error_rad >= np.pi / 2:
            raise ValueError(
                f"angular_error_rad must be below pi/2 (got {self.angular_error_rad!r})"
            )
        if self.noise not in ("none", "uniform", "bound"):
            raise ValueError(f"noise must be 'none', 'uniform' or 'bound' (got {self.noise!r})")
        if not isinstance(self.occlusion, bool | np.bool_):
            raise TypeError(f"occlusion must be True or False (got {self.occlusion!r})")


@dataclass
class Observation:
    """What the team senses at one instant.

    ``pairs`` is the true interaction graph (for metrics and recording only).
    The directed measurements are stored CSR-style: robot ``i``'s measured
    relative positions are ``measured[indptr[i]:indptr[i+1]]``. ``target``
    says whom each measurement is of; it exists for recording and tests, and
    unlabelled strategies must not use it.
    """

    pairs: np.ndarray
    indptr: np.ndarray
    target: np.ndarray
    measured: np.ndarray
    true_relative: np.ndarray

    @property
    def n(self) -> int:
        return len(self.indptr) - 1

    def of(self, i: int) -> np.ndarray:
        """Measured relative positions ``(k, dim)`` of the robots ``i`` senses."""
        return self.measured[self.indptr[i] : self.indptr[i + 1]]

    def degree(self) -> np.ndarray:
        return np.diff(self.indptr)

    def observer(self) -> np.ndarray:
        """Observer index of every measurement (length ``2 * len(pairs)``)."""
        return np.repeat(np.arange(self.n), self.degree())


def _occluded(positions: np.ndarray, pairs: np.ndarray, body_radius_m: float) -> np.ndarray:
    """Boolean per pair: a third robot's body hides the pair from each other.

    Candidate occluders of ``(i, k)`` are closer to both than ``d_ik <= range``,
    hence in range of ``i``: we scan only ``i``'s range-neighbours, so the cost
    is ``O(sum of degree^2)``, not all-pairs.
    """
    n = len(positions)
    m = len(pairs)
    if m == 0 or body_radius_m <= 0:
        return np.zeros(m, dtype=bool)
    both = np.concatenate([pairs, pairs[:, ::-1]])
    order = np.argsort(both[:, 0], kind="stable")
    nbr = both[order, 1]
    indptr = np.concatenate([[0], np.cumsum(np.bincount(both[:, 0], minlength=n))])
    i, k = pairs[:, 0], pairs[:, 1]
    pair_idx, entry = expand_rows(indptr, i)
    j = nbr[entry]
    pi, pk = i[pair_idx], k[pair_idx]
    keep = j != pk
    pair_idx, j, pi, pk = pair_idx[keep], j[keep], pi[keep], pk[keep]
    # squared distances only: |ij|^2 < |ik|^2, |kj|^2 < |ik|^2, and the distance from
    # j to the line i-k (its foot then lies inside the segment) below the body radius
    xi = positions[pi]
    ik = positions[pk] - xi
    ij = positions[j] - xi
    d2_ik = np.einsum("kd,kd->k", ik, ik)
    d2_ij = np.einsum("kd,kd->k", ij, ij)
    proj = np.einsum("kd,kd->k", ij, ik)
    d2_kj = d2_ik - 2.0 * proj + d2_ij
    perp2 = d2_ij - proj * proj / np.maximum(d2_ik, 1e-300)
    blocks = (d2_ij < d2_ik) & (d2_kj < d2_ik) & (perp2 < body_radius_m**2)
    out = np.zeros(m, dtype=bool)
    out[pair_idx[blocks]] = True
    return out


def sensed_pairs(
    positions: np.ndarray, sensor: SensorModel, world: World | None = None
) -> np.ndarray:
    """Undirected pairs ``(i, k)`` that sense each other (the true interaction graph)."""
    positions = np.ascontiguousarray(positions, dtype=float)
    pairs = pairs_within(positions, sensor.range_m)
    if len(pairs) == 0:
        return pairs
    keep = np.ones(len(pairs), dtype=bool)
    if world is not None and world.has_obstacles:
        keep &= world.segments_clear(positions[pairs[:, 0]], positions[pairs[:, 1]])
    if sensor.occlusion and sensor.body_radius_m > 0:
        if _use_kernel(len(positions)):
            hidden = _kernels().occluded_kernel(
                positions, pairs.astype(np.int64), float(sensor.body_radius_m)
            )
            keep &= ~hidden
        else:
            keep &= ~_occluded(positions, pairs, sensor.body_radius_m)
    return pairs[keep]


_NO_FIELD = np.zeros(0)


def _los_grid(world: World | None, sensor: SensorModel, n: int) -> Any:
    """The occupancy grid :func:`sensed_pairs` tests line of sight on, when
    :func:`~tether.sensing.robots_kernels.sense_grid_kernel` gives its pairs exactly.

    That is: a small team (compiled pair search, :func:`tether.jit.warm`), no occlusion,
    a world whose ``segments_clear`` is the grid's (samples every half cell, no
    clearance) and a C-ordered free mask (the compiled line of sight). ``None`` otherwise.
    """
    if world is None or not world.has_obstacles or world.grid is None or n > KERNEL_PAIRS_MAX_N:
        return None
    if sensor.occlusion and sensor.body_radius_m > 0:
        return None
    grid = world.grid
    if type(world).segments_clear is not World.segments_clear or not jit.warm():
        return None
    if type(grid).segments_clear is not OccupancyGrid.segments_clear:
        return None
    return grid if grid.free_mask().flags.c_contiguous else None


def _noisy(rel: np.ndarray, sensor: SensorModel, rng: np.random.Generator) -> np.ndarray:
    if sensor.noise == "none" or len(rel) == 0:
        return rel.copy()
    k = len(rel)
    if sensor.noise == "uniform":
        e_r = rng.uniform(-sensor.radial_error_m, sensor.radial_error_m, size=k)
        e_a = rng.uniform(-sensor.angular_error_rad, sensor.angular_error_rad, size=k)
    else:
        e_r = sensor.radial_error_m * rng.choice([-1.0, 1.0], size=k)
        e_a = sensor.angular_error_rad * rng.choice([-1.0, 1.0], size=k)
    dist = np.linalg.norm(rel, axis=1)
    direction = unit(rel)
    perp = random_perpendicular(rel, rng)
    rotated = np.cos(e_a)[:, None] * direction + np.sin(e_a)[:, None] * perp
    return rotated * np.maximum(dist + e_r, 0.0)[:, None]


def _noisy_compiled(rel: np.ndarray, sensor: SensorModel, rng: np.random.Generator) -> np.ndarray:
    """:func:`_noisy` with the arithmetic compiled: the same draws, in the same order.

    The errors and the 2-D perpendicular's signs come from one compiled call that
    draws them as the ``Generator`` calls of :func:`_noisy` would
    (:mod:`tether.sensing.draws_kernels`), the 3-D normals from numpy after them;
    ``cos``/``sin`` of the angular errors stay numpy's (so the values are the same).
    """
    if sensor.noise == "none" or len(rel) == 0:
        return rel.copy()
    k, dim = rel.shape
    draws = _draws_kernels()
    e_r, e_a, flip = draws.sensor_errors_kernel(
        k, draws.NOISE_CODES[sensor.noise], float(sensor.radial_error_m),
        float(sensor.angular_error_rad), dim == 2, draws.bitgen_addresses(rng),
    )  # fmt: skip
    normal = _NO_NORMALS if dim == 2 else rng.normal(size=(k, dim))
    return _kernels().noise_kernel(rel, e_r, np.cos(e_a), np.sin(e_a), flip, normal)


_NO_NORMALS = np.empty((0, 2))  # the 3-D draws' placeholder in 2-D


def _directed(pairs: np.ndarray, positions: np.ndarray, n: int) -> tuple[np.ndarray, ...]:
    """Both directions of ``pairs`` sorted by observer: directed pairs, CSR indptr, relatives."""
    directed = np.concatenate([pairs, pairs[:, ::-1]]) if len(pairs) else pairs.reshape(0, 2)
    order = np.lexsort((directed[:, 1], directed[:, 0]))
    directed = directed[order]
    indptr = np.concatenate([[0], np.cumsum(np.bincount(directed[:, 0], minlength=n))])
    rel = positions[directed[:, 1]] - positions[directed[:, 0]]
    return directed, indptr.astype(np.intp), rel


def observation_from_pairs(positions: np.ndarray, pairs: np.ndarray) -> Observation:
    """An exact (noise-free) observation of a given graph on nodes at ``positions``.

    For strategies whose links come from their own model (e.g. communication
    links on a grid map with a base station as an extra node).
    """
    positions = np.asarray(positions, dtype=float)
    pairs = np.asarray(pairs, dtype=np.intp).reshape(-1, 2)
    directed, indptr, rel = _directed(pairs, positions, len(positions))
    return Observation(pairs, indptr, directed[:, 1].astype(np.intp), rel.copy(), rel)


def sense(
    positions: np.ndarray,
    sensor: SensorModel,
    rng: np.random.Generator,
    world: World | None = None,
) -> Observation:
    """Sense the team: the interaction graph and every robot's noisy measurements."""
    positions = np.ascontiguousarray(positions, dtype=float)
    n = len(positions)
    if _use_kernel(n) and positions.ndim == 2 and positions.shape[1] in (2, 3):
        kernels = _kernels()
        grid = _los_grid(world, sensor, n)
        if n <= KERNEL_PAIRS_MAX_N and (world is None or not world.has_obstacles):
            radius = float(sensor.body_radius_m) if sensor.occlusion else 0.0
            if positions.shape[1] == 2 and kernels.numpy_trig_is_libm():  # one call
                draws = _draws_kernels()
                pairs, indptr, target, rel, measured = kernels.sense_noisy_kernel(
                    positions, float(sensor.range_m), radius, draws.NOISE_CODES[sensor.noise],
                    float(sensor.radial_error_m), float(sensor.angular_error_rad),
                    draws.bitgen_addresses(rng),
                )  # fmt: skip
                return Observation(pairs, indptr, target, measured, rel)
            pairs, indptr, target, rel = kernels.sense_pairs_kernel(
                positions, float(sensor.range_m), radius
            )
        elif grid is not None:  # range, line of sight and CSR in one call (same pairs)
            free = grid.free_mask()
            to_cells = 1.0 / grid.resolution_m
            field = grid.__dict__.get("distance_field_m")  # as segments_clear passes it
            if field is None or not field.flags.c_contiguous:
                field = _NO_FIELD
            pairs, indptr, target, rel = kernels.sense_grid_kernel(
                positions, float(sensor.range_m), free.reshape(-1),
                np.asarray(free.shape, dtype=np.int64), np.asarray(grid.origin_m, dtype=float),
                to_cells, 0.5, field.reshape(-1),
            )  # fmt: skip
        else:
            pairs = sensed_pairs(positions, sensor, world)
            indptr, target, rel = kernels.directed_kernel(pairs.astype(np.int64), positions, n)
        measured = _noisy_compiled(rel, sensor, rng)
        return Observation(
            pairs=pairs,
            indptr=indptr.astype(np.intp, copy=False),
            target=target.astype(np.intp, copy=False),
            measured=measured,
            true_relative=rel,
        )
    pairs = sensed_pairs(positions, sensor, world)
    directed, indptr, rel = _directed(pairs, positions, n)
    measured = _noisy(rel, sensor, rng)
    return Observation(
        pairs=pairs,
        indptr=indptr,
        target=directed[:, 1].astype(np.intp),
        measured=measured,
        true_relative=rel,
    )
