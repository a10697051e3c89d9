"""Parameter grids x seeds over one scenario, resumable, with a comparison table.

Each trial writes its own run folder ``<out>/<combo>/seed-<k>/``; a trial whose
``summary.json`` exists is not run again, so a killed sweep resumes where it
stopped without losing or redoing work (run folders are written atomically).
"""

from __future__ import annotations

import itertools
import json
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow.parquet as pq

from tether.config import Scenario, scenario_from_dict, set_dotted
from tether.record import RunFolder


@dataclass
class SweepResult:
    table: Path
    n_runs: int
    n_skipped: int
    figures: list[Path] = field(default_factory=list)


def combinations(sweep: dict[str, list[Any]]) -> list[dict[str, Any]]:
    """All combinations of the sweep grid, in a stable order (one empty dict if no grid)."""
    keys = list(sweep)
    return [dict(zip(keys, values, strict=True)) for values in itertools.product(*sweep.values())]


def combo_label(combo: dict[str, Any]) -> str:
    if not combo:
        return "base"
    return ",".join(f"{k.rsplit('.', 1)[-1]}={v}" for k, v in combo.items())


def trial_scenario(base: Scenario, combo: dict[str, Any]) -> Scenario:
    data = base.model_dump(mode="json")
    data.pop("sweep", None)
    for key, value in combo.items():
        set_dotted(data, key, value)
    return scenario_from_dict(data, f"{base.source} [{combo_label(combo)}]", base.base_dir)


def run_sweep(
    scenario: Scenario,
    out_dir: str | Path,
    *,
    seeds: int = 1,
    progress: Callable[[str], None] | None = None,
) -> SweepResult:
    """Run every combination of ``scenario.sweep`` for ``seeds`` seeds (sequentially)."""
    from tether.runner import run

    out = Path(out_dir)
    rows: list[dict[str, Any]] = []
    n_runs = n_skipped = 0
    for combo in combinations(scenario.sweep):
        trial = trial_scenario(scenario, combo)
        for k in range(seeds):
            seed = scenario.seed + k
            run_dir = out / combo_label(combo) / f"seed-{seed}"
            summary_file = run_dir / "summary.json"
            if summary_file.exists():
                summary = json.loads(summary_file.read_text())
                n_skipped += 1
            else:
                if progress:
                    progress(f"{combo_label(combo)} seed {seed} ...")
                summary = run(trial, out_dir=run_dir, seed=seed, figures=False).summary
            n_runs += 1
            flat = {k2: v for k2, v in summary.items() if not isinstance(v, dict | list)}
            rows.append(
                {**{f"param:{k2}": v for k2, v in combo.items()}, **flat, "run_dir": str(run_dir)}
            )
    folder = RunFolder(out)
    table = folder.write_rows("sweep.parquet", rows)
    figures = [folder.save_figure(links_figure(rows, scenario.team.n_robots), "links.png")]
    return SweepResult(table, n_runs, n_skipped, figures)


def links_figure(rows: list[dict[str, Any]], n_robots: int) -> Any:
    """Links over time of the first seed of each combination (e.g. the silent paper's Fig. 5)."""
    from tether.viz.plots import links_over_time

    series: dict[str, tuple[np.ndarray, np.ndarray]] = {}
    for row in rows:
        label = combo_label({k[6:]: v for k, v in row.items() if k.startswith("param:")})
        steps_file = Path(row["run_dir"]) / "steps.parquet"
        if label in series or not steps_file.exists():
            continue
        table = pq.read_table(steps_file, columns=["t_s", "n_links"]).to_pydict()
        series[label] = (np.asarray(table["t_s"]), np.asarray(table["n_links"]))
    return links_over_time(series, n_robots)
