"""``tether list``: every built-in name a user can type, each with what it is."""

from __future__ import annotations

import inspect

from tether.config import builtin_scenarios, paper_campaigns, read_scenario_data
from tether.errors import TetherError
from tether.plugins import load_builtins
from tether.registry import LINK_MODELS, SCENES, STRATEGIES, Registry

#: each section: its title, where the names go, and the names with their descriptions
SECTIONS = (
    ("scenarios", "tether run NAME"),
    ("campaigns", "tether sweep NAME [--quick]"),
    ("strategies", "strategy.name"),
    ("scenes", "world.scene"),
    ("link models", "strategy.params.link_model"),
)


def _scenario_description(name: str) -> str:
    try:
        data, _, _ = read_scenario_data(name)
    except TetherError:
        return "(cannot be read)"
    return str(data.get("description") or "")


def _first_line(registry: Registry, name: str) -> str:
    """The first line of the docstring of what ``name`` registers (its module imported)."""
    try:
        doc = inspect.getdoc(registry.get(name)) or ""
    except Exception as exc:  # a plug-in that fails to import is listed with why
        return f"(cannot be loaded: {type(exc).__name__})"
    return doc.splitlines()[0].replace("``", "") if doc else ""


def listing() -> list[tuple[str, str, list[tuple[str, str]]]]:
    """``(section, where the names go, [(name, description), ...])`` for every section."""
    load_builtins()
    rows = {
        "scenarios": [(n, _scenario_description(n)) for n in builtin_scenarios()],
        "campaigns": [(n, _scenario_description(n)) for n in paper_campaigns()],
        "strategies": [(n, _first_line(STRATEGIES, n)) for n in STRATEGIES.names()],
        "scenes": [(n, _first_line(SCENES, n)) for n in SCENES.names()],
        "link models": [(n, _first_line(LINK_MODELS, n)) for n in LINK_MODELS.names()],
    }
    return [(title, where, rows[title]) for title, where in SECTIONS]


def listing_lines() -> list[str]:
    """The text of ``tether list``: one section per kind, one line per name."""
    sections = listing()
    width = max(len(name) for _, _, rows in sections for name, _ in rows) + 2
    lines: list[str] = []
    for title, where, rows in sections:
        lines.append(f"{title} ({where}):")
        lines += [f"  {name:<{width}}{text}".rstrip() for name, text in rows]
        lines.append("")
    return lines[:-1]
