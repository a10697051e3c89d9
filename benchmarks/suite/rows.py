"""Every row module, imported so that its rows register (in the order they run)."""

from suite import (  # noqa: F401
    campaign,
    connectivity,
    envs,
    fiedler,
    paths,
    recurrent,
    silent,
    steiner,
    viewing,
)
