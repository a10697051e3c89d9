"""Help text as a terminal should show it: paragraphs that flow to the window's width.

A docstring's lines end where the source wraps them; shown as they are, a help
paragraph breaks mid-sentence at fixed places whatever the terminal's width.
:func:`flow` joins each paragraph into one line (blank lines still separate
paragraphs) and :func:`summary` gives the first sentence for the list of commands.
"""

from __future__ import annotations

import inspect
import re


def flow(doc: str | None) -> str:
    """``doc`` with each paragraph on one line, paragraphs separated by a blank line."""
    text = inspect.cleandoc(doc or "")
    paragraphs = re.split(r"\n\s*\n", text)
    return "\n\n".join(" ".join(p.split()) for p in paragraphs if p.strip())


def summary(doc: str | None) -> str:
    """The first sentence of ``doc`` (its first paragraph if it has no full stop)."""
    first = flow(doc).split("\n\n", 1)[0]
    match = re.match(r"(.+?[.!?])(\s|$)", first)
    return match.group(1) if match else first
