"""The settings of the recurrent-connectivity report: labels of maps and settings.

A *setting* is one combination of a paper campaign's axes other than the map, named by
a label: ``apx_t12_timed`` / ``ilp_t12_instant`` (Fig. 4: method and whether planning
time is counted, ``paper/recurrent_fig4``), ``theta<k>`` (Figs. 5-6,
``paper/recurrent_fig5_6``), ``utility_<coordination>`` (the Utility baseline,
``paper/recurrent_fig5_6_utility``) and ``theta1_<binding>`` (the relay binding at
theta = 1, ``paper/recurrent_relay_binding``). :func:`setting_label` gives a trial's
label from its campaign and values.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

__all__ = ["CAMPAIGNS", "MAP_LABELS", "display_name", "setting_label"]

#: map file stem -> the paper's name of the map
MAP_LABELS = {"grass": "Cluttered", "offices": "Office", "open": "Open"}

#: campaign kind -> the paper campaign it is run from (``tether sweep paper/<name>``)
CAMPAIGNS = {
    "fig4": "paper/recurrent_fig4",
    "fig5_6": "paper/recurrent_fig5_6",
    "utility": "paper/recurrent_fig5_6_utility",
    "relay": "paper/recurrent_relay_binding",
}


def setting_label(kind: str, params: Mapping[str, Any]) -> str:
    """The label of a trial of campaign ``kind`` whose strategy parameters are ``params``."""
    if kind == "fig4":
        mode = "timed" if params.get("count_planning_time") else "instant"
        return f"{params.get('method', 'apx')}_t12_{mode}"
    if kind == "fig5_6":
        return f"theta{params.get('theta', 1)}"
    if kind == "utility":
        return f"utility_{params.get('coordination', 'greedy')}"
    if kind == "relay":
        return f"theta1_{params.get('relay_binding', 'assigned')}"
    raise ValueError(f"unknown campaign kind {kind!r}; expected one of: {', '.join(CAMPAIGNS)}")


def display_name(label: str) -> str:
    """``theta3`` -> "θ = 3", ``utility_none`` -> "Utility (none)"."""
    if label.startswith("utility"):
        return "Utility" + (f" ({label[8:]})" if label != "utility" else "")
    if label.startswith("theta1_"):
        return f"θ = 1, P_f of {label[7:]}"
    return f"θ = {label[5:]}"
