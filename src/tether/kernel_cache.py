"""Fill numba's cache with every compiled kernel of tether: ``python -m tether.kernel_cache``.

Each kernel module has a ``warm_up()`` that calls its kernels once on a tiny input of
the types its callers pass; :func:`warm_up` runs all of them, so that a benchmark (or
a worker of a campaign) can pay numba's start-up up front and measure it on its own,
then writes the marker of :func:`tether.jit.marker` (the ``auto`` switch of
:mod:`tether.jit` waits for it). The ``auto`` switch starts this module as a child
process (:data:`tether.jit.COMPILE_COMMAND`) when the cache is cold.
"""

from __future__ import annotations

import time

from tether import jit


def warm_up() -> float:
    """Compile or load (from numba's cache) every kernel, then write the marker.

    Returns the seconds it took.
    """
    start = time.perf_counter()
    # imports here: numba only once asked for
    from tether.comm_kernels import warm_up as comm
    from tether.continuous.connectivity.bookkeep_kernels import warm_up as bookkeep
    from tether.continuous.connectivity.dynamics_kernels import warm_up as dynamics
    from tether.continuous.connectivity.kernels import warm_up as connectivity
    from tether.continuous.exploration.recruit_kernels import warm_up as recruit
    from tether.continuous.exploration.reference_filter_kernels import warm_up as reference
    from tether.continuous.exploration.round_kernels import warm_up as rounds
    from tether.continuous.exploration.step_kernels import warm_up as steps
    from tether.continuous.exploration.substep_kernels import warm_up as substep
    from tether.continuous.exploration.tracking_kernels import warm_up as tracking
    from tether.graph.grid_kernels import warm_up as grid
    from tether.graph.link_kernels import warm_up as links
    from tether.graph.metrics_kernels import warm_up as metrics
    from tether.paths.astar_kernels import warm_up as astar
    from tether.paths.geodesic_kernels import warm_up as geodesic
    from tether.recurrent.planning.apx_kernels import warm_up as apx
    from tether.recurrent.planning.expgraph_kernels import warm_up as expgraph
    from tether.recurrent.planning.ilp_kernels import warm_up as ilp
    from tether.recurrent.planning.steiner_kernels import warm_up as steiner
    from tether.sensing.depth_kernels import warm_up as depth
    from tether.sensing.draws_kernels import warm_up as draws
    from tether.sensing.robots_kernels import warm_up as sensing
    from tether.silent.steering_kernels import warm_up as steering
    from tether.world.los_kernels import warm_up as line_of_sight

    for module_warm_up in (connectivity, substep, tracking, steps, line_of_sight, dynamics,
                           rounds, bookkeep, comm, steiner, ilp, steering, sensing, draws, grid,
                           metrics, astar, links, geodesic, expgraph, depth, apx,
                           reference, recruit):  # fmt: skip
        module_warm_up()
    seconds = time.perf_counter() - start
    jit.write_marker(seconds)
    return seconds


if __name__ == "__main__":  # the background warm-up of tether.jit's ``auto`` switch
    import contextlib
    import os

    with contextlib.suppress(AttributeError, OSError):
        os.nice(10)
    warm_up()
