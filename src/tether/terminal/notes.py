"""Notes under a run's summary: what the user should know about the result.

A team that lost connectivity is said so, with how often and when it first happened; a
strategy whose guarantee holds in free space only (``free_space_guarantee``, a class
attribute) adds that sentence when its scene has obstacles.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.parquet as pq

#: scenes with nothing in the way (every other scene has obstacles)
OPEN_SCENES = ("free", "empty")


def run_notes(path: Path, summary: dict[str, Any], scenario: Any, strategy: type) -> list[str]:
    """Lines for the end of ``tether run`` (possibly none)."""
    if summary.get("connected_all_steps") is not False:
        return []
    notes = []
    steps_file = Path(path) / "steps.parquet"
    if steps_file.exists():
        table = pq.read_table(steps_file, columns=["step", "connected"]).to_pydict()
        step = np.asarray(table["step"])
        apart = ~np.asarray(table["connected"], dtype=bool)
        if apart.any():
            notes.append(
                f"the team was disconnected at {int(apart.sum()):,} of {len(step):,} steps "
                f"(first at step {int(step[apart][0]):,})"
            )
    guarantee = getattr(strategy, "free_space_guarantee", None)
    if guarantee and scenario.world.scene not in OPEN_SCENES:
        notes.append(guarantee)
    return notes
