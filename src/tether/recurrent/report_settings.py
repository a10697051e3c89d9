"""The settings of the recurrent-connectivity report: labels, paper files and run folders.

Shared by :mod:`tether.recurrent.report` (which runs them) and
:mod:`tether.recurrent.report_tables` (which prints the doc tables from the run
folders). The values of a setting live in the paper campaign files
(``scenarios/paper/recurrent_*.yaml``); a label here only says which file and which
combination of its ``sweep:`` axes it is (:class:`Setting`), plus, for the issue-13
variants, the one value the label spells out. Labels with the same scenario share one
set of run folders (:data:`SAME_RUNS`): the spelled-out labels (``theta1_assigned``,
``utility_greedy``) name the folders and the short ones (``theta1``, ``utility``: the
files' defaults) reuse them.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

__all__ = [
    "MAP_LABELS",
    "SAME_RUNS",
    "Setting",
    "display_name",
    "run_dir",
    "settings_table",
]

MAP_LABELS = {"grass": "Cluttered", "offices": "Office", "open": "Open"}

#: the paper files (``scenarios/paper/<name>.yaml``) the settings come from
FIG4, FIG5_6, UTILITY = "recurrent_fig4", "recurrent_fig5_6", "recurrent_fig5_6_utility"

#: labels whose scenario is another label's: they share its run folders (the report checks)
SAME_RUNS = {"apx_t12_instant": "theta12", "theta1": "theta1_assigned", "utility": "utility_greedy"}


@dataclass(frozen=True)
class Setting:
    """One setting: a combination of a paper file's sweep, and the values a variant sets.

    ``pick`` gives the values of the file's axes other than the map
    (``world.params.path``) that select the combination; ``variant`` the dotted keys
    set on top of it (the issue-13 variants the paper files do not sweep).
    """

    file: str
    pick: dict[str, Any] = field(default_factory=dict)
    variant: dict[str, Any] = field(default_factory=dict)


def settings_table(thetas: tuple[int, ...] = (1, 3, 6, 9, 12)) -> dict[str, Setting]:
    """Every setting by label (Fig. 4, Figs. 5-6, relay binding, Utility both ways)."""
    out: dict[str, Setting] = {}
    for mode, timed in (("timed", True), ("instant", False)):
        for method in ("apx", "ilp"):
            pick = {"strategy.params.method": method, "strategy.params.count_planning_time": timed}
            out[f"{method}_t12_{mode}"] = Setting(FIG4, pick)
    for th in thetas:
        out[f"theta{th}"] = Setting(FIG5_6, {"strategy.params.theta": th})
    # relay binding both ways at theta = 1 (the measurement behind the default)
    for binding in ("assigned", "frontiers"):
        variant = {"strategy.params.relay_binding": binding}
        out[f"theta1_{binding}"] = Setting(FIG5_6, {"strategy.params.theta": 1}, variant)
    out["utility"] = Setting(UTILITY)
    for coordination in ("greedy", "none"):
        variant = {"strategy.params.coordination": coordination}
        out[f"utility_{coordination}"] = Setting(UTILITY, {}, variant)
    return out


def run_dir(out: Path, m: str, label: str, k: int) -> Path:
    """Run folder of ``label`` on map ``m``, seed ``k``; labels of one scenario share it.

    ``apx_t12_instant`` (Fig. 4b) and ``theta12`` (Figs. 5-6) are the same
    scenario; with the same seed the simulation is deterministic, so it runs once
    (under ``theta12``); ``theta1`` runs under ``theta1_assigned`` and ``utility``
    under ``utility_greedy`` (:data:`SAME_RUNS`).
    """
    return Path(out) / "runs" / m / SAME_RUNS.get(label, label) / f"seed-{k}"


def display_name(label: str) -> str:
    """``theta3`` -> "θ = 3", ``utility_none`` -> "Utility (none)"."""
    if label.startswith("utility"):
        return "Utility" + (f" ({label[8:]})" if label != "utility" else "")
    if label.startswith("theta1_"):
        return f"θ = 1, P_f of {label[7:]}"
    return f"θ = {label[5:]}"
