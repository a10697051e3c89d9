"""Synthetic run folders for the viewing tests (animate, view, export).

A team of ``n_robots`` moves smoothly (each robot wandering around its place
in a drifting formation) through free space for ``n_steps``
steps; links are the pairs within ``range_m``. Written with the same layout as
``tether run`` (scenario.yaml, steps/robots/links Parquet, summary.json), so the
readers cannot tell it from a real run, but any size can be made in a second.
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import yaml


def pos_shape(n_steps: int, n_robots: int, dim: int) -> tuple[int, int, int]:
    return (n_steps + 1, n_robots, dim)


def make_run_folder(
    path: Path,
    *,
    n_robots: int = 8,
    n_steps: int = 50,
    dim: int = 2,
    range_m: float = 12.0,
    dt_s: float = 0.5,
    roles: bool = False,
    seed: int = 0,
) -> dict[str, np.ndarray]:
    """Write the run folder; returns ``positions`` ``(T, n, dim)``, ``steps``, ``n_links``."""
    rng = np.random.default_rng(seed)
    path.mkdir(parents=True, exist_ok=True)
    t = np.arange(n_steps + 1, dtype=float)[:, None, None]
    offset = rng.uniform(-1.2 * range_m, 1.2 * range_m, size=(1, n_robots, dim))
    phase = rng.uniform(0, 2 * np.pi, size=(1, n_robots, dim))
    wander = 0.25 * range_m * np.sin(0.02 * t + phase)
    centre = np.zeros((n_steps + 1, 1, dim))
    centre[:, 0, 0] = 0.05 * t[:, 0, 0]
    centre[:, 0, 1] = 10 * np.sin(0.002 * t[:, 0, 0])
    jitter = rng.normal(scale=0.01 * range_m, size=pos_shape(n_steps, n_robots, dim))
    pos = centre + offset + wander + jitter  # jitter: sensing noise, as in real runs
    if dim == 3:
        pos[:, :, 2] = 3.0 + 0.3 * pos[:, :, 2]
    steps = np.arange(n_steps + 1)
    scenario = {
        "name": "synthetic",
        "seed": seed,
        "world": {"scene": "free", "dim": dim},
        "team": {"n_robots": n_robots},
        "sensing": {"range_m": range_m},
        "sim": {"dt_s": dt_s, "max_steps": n_steps},
        "strategy": {"name": "connectivity", "params": {"rs_m": range_m}},
    }
    (path / "scenario.yaml").write_text(yaml.safe_dump(scenario))
    robot_cols = {
        "step": np.repeat(steps, n_robots),
        "robot": np.tile(np.arange(n_robots), len(steps)),
        "x_m": pos[:, :, 0].ravel(),
        "y_m": pos[:, :, 1].ravel(),
    }
    if dim == 3:
        robot_cols["z_m"] = pos[:, :, 2].ravel()
    if roles:
        names = np.array(["leader", "relay", "explorer"])
        robot_cols["role"] = names[
            (np.arange(n_robots)[None, :] + steps[:, None] // 10) % 3
        ].ravel()
    pq.write_table(pa.table(robot_cols), path / "robots.parquet")
    iu, ju = np.triu_indices(n_robots, 1)
    d = np.linalg.norm(pos[:, iu] - pos[:, ju], axis=2)  # (T, pairs)
    ts, ps = np.nonzero(d <= range_m)
    links = {"step": steps[ts], "i": iu[ps], "j": ju[ps]}
    pq.write_table(pa.table(links), path / "links.parquet")
    n_links = np.bincount(ts, minlength=len(steps))
    step_cols = {
        "step": steps,
        "t_s": steps * dt_s,
        "n_links": n_links,
        "lambda2": 0.1 + n_links / max(n_links.max(), 1),
        "connected": np.ones(len(steps), dtype=bool),
    }
    pq.write_table(pa.table(step_cols), path / "steps.parquet")
    pq.write_table(pa.table({"step": pa.array([], pa.int64())}), path / "events.parquet")
    summary = {
        "scenario": "synthetic",
        "strategy": "connectivity",
        "n_robots": n_robots,
        "dim": dim,
        "steps": n_steps,
        "seed": seed,
    }
    (path / "summary.json").write_text(json.dumps(summary))
    return {"positions": pos, "steps": steps, "n_links": n_links}
