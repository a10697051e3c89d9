"""The quick size of a sweep: a scenario's ``sweep.quick`` entry applied to its data.

``tether sweep FILE --quick`` and ``tether validate FILE --quick`` run the experiment at
the size its ``quick`` entry gives (grammar: :mod:`tether.sweepspec`): the quick
``set`` keys change the scenario, the quick axes and seeds replace the sweep's. The
quick scenario is named ``<name>-quick``, so its scenario hash differs from the full
one and the trials of the two sizes never share a sweep folder (the store refuses
the mix, naming ``name`` as the change).
"""

from __future__ import annotations

import copy
from pathlib import Path
from typing import Any

from tether.config import (
    MAX_NAME_BYTES,
    Scenario,
    apply_overrides,
    read_scenario_data,
    scenario_from_dict,
    set_dotted,
)
from tether.errors import ScenarioError
from tether.sweepspec import SweepError, parse_sweep, quick_block

__all__ = ["QUICK_SUFFIX", "load_scenario_at", "quick_data"]

#: appended to the scenario name (and the default sweep folder) of the quick size
QUICK_SUFFIX = "-quick"


def quick_data(data: dict[str, Any], label: str, base_dir: Path | None = None) -> dict[str, Any]:
    """Scenario data at its quick size: ``quick.set`` applied, the quick sweep block, name.

    Parameters
    ----------
    data : dict
        Raw scenario data (e.g. from :func:`tether.config.read_scenario_data`).
    label : str
        The scenario's file or name, for messages.

    Raises
    ------
    ScenarioError
        ``<file>: sweep.quick...: <problem and fix>``: no quick entry, a malformed one,
        or a ``quick.set`` value the scenario refuses.
    """
    block = data.get("sweep") if isinstance(data.get("sweep"), dict) else {}
    try:
        quick = quick_block(block)
        settings = parse_sweep(block).quick.set  # type: ignore[union-attr]
    except SweepError as exc:
        raise ScenarioError(" ".join(f"{label}: {exc}".split())) from None
    out = copy.deepcopy(data)
    for key, value in settings.items():
        set_dotted(out, key, value)
    out["sweep"] = quick
    name = str(out.get("name", "scenario"))
    while name and len((name + QUICK_SUFFIX).encode("utf-8", "surrogatepass")) > MAX_NAME_BYTES:
        name = name[:-1]
    out["name"] = name + QUICK_SUFFIX
    try:
        scenario_from_dict(out, label, base_dir)
    except ScenarioError as exc:
        try:
            scenario_from_dict(data, label, base_dir)
        except ScenarioError:
            raise exc from None  # the full size is refused too: not the quick entry's fault
        problem = str(exc).removeprefix(f"{label}: ")
        raise ScenarioError(f"{label}: sweep.quick.set: {problem}") from None
    return out


def load_scenario_at(
    path_or_name: str | Path, *, quick: bool = False, overrides: list[str] | None = None
) -> Scenario:
    """Load a scenario at its full or quick size, then apply ``--set`` overrides.

    Overrides come last, so ``--set`` wins over the quick entry's ``set``. At the quick
    size the scenario's source reads ``<file> (quick size)``, so later messages (a
    refused axis value, a combination that does not build) say which size they are about.
    """
    data, label, base = read_scenario_data(path_or_name)
    if quick:
        data = quick_data(data, label, base)
    if overrides:
        data = apply_overrides(data, overrides, label)
    return scenario_from_dict(data, f"{label} (quick size)" if quick else label, base)
