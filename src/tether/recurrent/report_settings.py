"""The settings of the recurrent-connectivity report and where their runs live.

Shared by :mod:`tether.recurrent.report` (which runs them) and
:mod:`tether.recurrent.report_tables` (which prints the doc tables from the run
folders). A setting is a small dict; settings with identical dicts share one set of
run folders, named after the *last* label that has that dict, so spelled-out labels
(``theta1_assigned``, ``utility_greedy``) name the folders and the short ones
(``theta1``, ``utility``: the defaults) reuse them.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

__all__ = [
    "DEFAULT_BINDING",
    "DEFAULT_COORDINATION",
    "MAP_LABELS",
    "display_name",
    "run_dir",
    "settings_table",
]

MAP_LABELS = {"grass": "Cluttered", "offices": "Office", "open": "Open"}

#: the defaults of the registered strategies, spelled out so a run folder's setting is explicit
DEFAULT_BINDING = "assigned"
DEFAULT_COORDINATION = "greedy"


def settings_table(thetas: tuple[int, ...] = (1, 3, 6, 9, 12)) -> dict[str, dict[str, Any]]:
    """Every setting by label (Fig. 4, Figs. 5-6, relay binding, Utility both ways)."""

    def rec(theta: int, method: str, timed: bool, binding: str = DEFAULT_BINDING) -> dict:
        return {"kind": "recurrent", "theta": theta, "method": method, "timed": timed,
                "binding": binding}  # fmt: skip

    out: dict[str, dict[str, Any]] = {
        "apx_t12_timed": rec(12, "apx", True),
        "ilp_t12_timed": rec(12, "ilp", True),
        "apx_t12_instant": rec(12, "apx", False),
        "ilp_t12_instant": rec(12, "ilp", False),
    }
    for th in thetas:
        out[f"theta{th}"] = rec(th, "apx", False)
    # relay binding both ways at theta = 1 (the measurement behind the default)
    for binding in ("assigned", "frontiers"):
        out[f"theta1_{binding}"] = rec(1, "apx", False, binding)
    out["utility"] = {"kind": "utility", "coordination": DEFAULT_COORDINATION}
    for coordination in ("greedy", "none"):
        out[f"utility_{coordination}"] = {"kind": "utility", "coordination": coordination}
    return out


def run_dir(out: Path, m: str, label: str, settings: dict[str, dict[str, Any]], k: int) -> Path:
    """Run folder of ``label`` on map ``m``, seed ``k``; identical settings share it.

    ``apx_t12_instant`` (Fig. 4b) and ``theta12`` (Figs. 5-6) are the same
    setting; with the same seed the simulation is deterministic, so it runs once
    (under ``theta12``); ``theta1`` runs under ``theta1_<default binding>``.
    """
    same = [name for name, s in settings.items() if s == settings[label]]
    return Path(out) / "runs" / m / same[-1] / f"seed-{k}"


def display_name(label: str) -> str:
    """``theta3`` -> "θ = 3", ``utility_none`` -> "Utility (none)"."""
    if label.startswith("utility"):
        return "Utility" + (f" ({label[8:]})" if label != "utility" else "")
    if label.startswith("theta1_"):
        return f"θ = 1, P_f of {label[7:]}"
    return f"θ = {label[5:]}"
