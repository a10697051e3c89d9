"""Free points and clear segments of a world, compiled (numba), for :mod:`.vector_kernels`.

``world`` is the tuple :func:`tether.envs.vector.world_arrays` makes: whether there is
a grid, its raveled free mask, shape, origin, cells per metre and distance field, whether
there is a box, the box, and the cell size. The answers are those of
:meth:`tether.world.world.World.points_free` and
:meth:`~tether.world.world.World.segments_clear` (the grid's line of sight samples every half
cell, :func:`tether.world.los_kernels.segment_free_kernel`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tether.world.los_kernels import segment_free_kernel


@njit(cache=True)
def point_free(p, has_grid, free, shape, origin, res, has_bounds, bounds):  # noqa: ANN001, ANN201
    """``World.points_free`` of one point: inside the box and in a free cell."""
    dim = len(p)
    if has_bounds:
        for c in range(dim):
            if p[c] < bounds[0, c] or p[c] > bounds[1, c]:
                return False
    if has_grid:
        flat = 0
        for c in range(dim):
            x = int(math.floor((p[c] - origin[c]) / res))
            if x < 0 or x >= shape[c]:
                return False
            flat = flat * shape[c] + x
        return free[flat]
    return True


@njit(cache=True)
def segment_clear(a, b, has_grid, free, shape, origin, to_cells, field):  # noqa: ANN001, ANN201
    if not has_grid:
        return True
    dim = len(a)
    aa = np.empty((1, dim))
    bb = np.empty((1, dim))
    for c in range(dim):
        aa[0, c] = (a[c] - origin[c]) * to_cells
        bb[0, c] = (b[c] - origin[c]) * to_cells
    return segment_free_kernel(free, shape, aa, bb, 0.5, field, to_cells)[0]
