"""The helpers' forces of a sub-step, compiled (numba, lazy).

The fast path, used when :func:`tether.jit.enabled`, of
:func:`tether.continuous.exploration.recruit.help_rows`: each helper's row of the
external force becomes :func:`~tether.continuous.exploration.recruit.help_force`'s
``sat(k_p (d - keep) u - k_v v, F_max)`` (minus ``(1 - g) f_lambda`` with a
``help_lambda_factor`` ``g``), in the numpy reference's operations and order (the
distance and the saturation norm summed in coordinate order, :func:`row_norm`), so the
same bits (``tests/test_multi_target_recruit.py``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from tether.continuous.connectivity.pair_kernels import row_norm


@njit(cache=True)
def help_rows_kernel(q, v, f, f_lambda, helpers, parent_m, keep_m, kp, kv, max_force_n, factor):  # noqa: ANN001, ANN201, PLR0913
    """Replace the rows ``helpers`` of ``f`` in place (``factor`` NaN: no scaling)."""
    dim = q.shape[1]
    gap = np.empty(dim)
    pull = np.empty(dim)
    saturated = math.isfinite(max_force_n)
    for k in range(len(helpers)):
        i = helpers[k]
        for c in range(dim):
            gap[c] = parent_m[k, c] - q[i, c]
        d = row_norm(gap)
        if d > keep_m:
            gain = kp * (d - keep_m)
            safe = d if (d >= 1e-12 or d != d) else 1e-12  # numpy.maximum(d, 1e-12)
            for c in range(dim):
                pull[c] = gain * gap[c] / safe - kv * v[i, c]
        else:
            pull[:] = 0.0
        scale = 1.0
        if saturated:  # numpy.minimum(1, F / numpy.maximum(|pull|, 1e-300))
            norm = row_norm(pull)
            ratio = max_force_n / (norm if (norm >= 1e-300 or norm != norm) else 1e-300)
            scale = 1.0 if ratio >= 1.0 else ratio
        for c in range(dim):
            f[i, c] = pull[c] * scale  # scale 1.0 unsaturated: exact
            if factor == factor:
                f[i, c] = f[i, c] - (1.0 - factor) * f_lambda[i, c]


def warm_up() -> None:
    """Compile (or load) the kernel for 2-D and 3-D teams."""
    helpers = np.array([0, 2], dtype=np.int64)
    for dim in (2, 3):
        q = np.zeros((3, dim))
        parent = np.ones((2, dim)) * 5.0
        for factor in (np.nan, 0.5):
            help_rows_kernel(q, q, np.zeros((3, dim)), q, helpers, parent, 2.5, 4.0, 4.0, 10.0,
                             factor)  # fmt: skip
