"""Every row module, imported so that its rows register; :data:`ORDER` is the order in
which a full run runs them and the tables show them (what a run costs first, then a
campaign, then the peers)."""

from suite import campaign, connectivity, envs, fiedler, paths, recurrent, silent, steiner, viewing
from suite.core import ROWS

MODULES = (campaign, connectivity, envs, fiedler, paths, recurrent, silent, steiner, viewing)
ORDER = (
    "kernels_compile",
    "run_startup",
    "silent_step",
    "connectivity_step",
    "multi_target_trial",
    "recurrent_grass",
    "viewing",
    "sweep",
    "build_reuse",
    "placement",
    "planning",
    "paths",
    "steiner_random",
    "steiner_steinlib",
    "steiner_scaling",
    "fiedler_small",
    "envs",
)
if set(ORDER) != set(ROWS):
    raise RuntimeError(f"suite.rows.ORDER and the registered rows differ: {set(ORDER) ^ set(ROWS)}")
_registered = dict(ROWS)
ROWS.clear()
ROWS.update((name, _registered[name]) for name in ORDER)
