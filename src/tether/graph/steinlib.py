"""A strict reader of SteinLib's STP format (Steiner tree problems in graphs).

SteinLib (Koch, Martin and Voss, https://steinlib.zib.de) is the public library of
Steiner tree instances with known optima; its file format is described at
https://steinlib.zib.de/format.php. This module reads the part of it that states an
undirected Steiner problem in graphs (SPG), so that
:func:`tether.recurrent.planning.steiner.steiner_tree` can be checked or timed on
those instances::

    33D32945 STP File, STP Format Version 1.0
    SECTION Comment
    Name "B01"
    END
    SECTION Graph
    Nodes 50
    Edges 63
    E 2 8 8
    ...
    END
    SECTION Terminals
    Terminals 9
    T 48
    ...
    END
    EOF

Read: the magic first line, ``SECTION Graph`` (``Nodes n``, ``Edges m``, then ``m``
lines ``E u v w``), ``SECTION Terminals`` (``Terminals k``, then ``k`` lines ``T v``)
and the closing ``EOF``. Vertices are numbered ``1..n``; keywords are case-insensitive.
Ignored: ``SECTION Comment`` and any section this reader does not know (coordinates,
presolve, ...). Anything else is refused with a :class:`ValueError` that names the
file and line: a keyword the SPG does not have (arcs ``A``, a ``Root``, prizes, or a
non-standard ``Optimal`` line in the Graph section), a count that does not match its
lines, a vertex outside ``1..n``, a self-loop, a repeated edge or terminal, a
negative or non-finite weight, a section without ``END``, a missing ``EOF``.
"""

from __future__ import annotations

import math
import os
from collections.abc import Iterator
from pathlib import Path
from typing import NamedTuple

import networkx as nx

__all__ = ["MAGIC", "SteinerInstance", "parse_stp", "read_stp"]

#: the first word of every STP file (SteinLib's magic number)
MAGIC = "33D32945"


class SteinerInstance(NamedTuple):
    """A Steiner problem in graphs, as read by :func:`read_stp`."""

    graph: nx.Graph
    """Vertices ``1..n`` (isolated ones too), edge attribute ``weight`` (int or float)."""
    terminals: list[int]
    """The terminals, in the file's order."""


class _Lines:
    """The non-blank lines of an STP text as ``(number, words)``, with error messages."""

    def __init__(self, text: str, source: str) -> None:
        self.source = source
        self._it: Iterator[tuple[int, str]] = (
            (k, line) for k, line in enumerate(text.splitlines(), start=1) if line.strip()
        )
        self.number = 0
        self.line = ""

    def next(self, what: str) -> list[str]:
        """The words of the next non-blank line; ``what`` names what was expected."""
        try:
            self.number, self.line = next(self._it)
        except StopIteration:
            raise ValueError(f"{self.source}: the file ends where {what} was expected") from None
        return self.line.split()

    def more(self) -> bool:
        """Move to the next non-blank line if there is one (then it is the current line)."""
        try:
            self.number, self.line = next(self._it)
        except StopIteration:
            return False
        return True

    def error(self, message: str) -> ValueError:
        """A ``ValueError`` naming the current line."""
        return ValueError(f"{self.source}:{self.number}: {message}: {self.line.strip()!r}")


def read_stp(path: str | os.PathLike[str]) -> SteinerInstance:
    """Read an undirected Steiner problem from a SteinLib ``.stp`` file.

    Parameters
    ----------
    path
        The file (see the module docstring and https://steinlib.zib.de/format.php).

    Returns
    -------
    SteinerInstance
        ``(graph, terminals)``: vertices ``1..n``, edge weights in ``weight``.

    Raises
    ------
    ValueError
        On anything the format does not allow or this reader does not know in the Graph
        and Terminals sections; the message names the file and the line.
    """
    path = Path(path)
    return parse_stp(path.read_text(), source=str(path))


def parse_stp(text: str, source: str = "<stp>") -> SteinerInstance:
    """Read an undirected Steiner problem from the text of an STP file.

    Parameters
    ----------
    text
        The whole file.
    source
        The name used in error messages.

    Returns
    -------
    SteinerInstance
        As :func:`read_stp`.

    Raises
    ------
    ValueError
        As :func:`read_stp`.
    """
    lines = _Lines(text, source)
    words = lines.next("the STP header")
    if words[0].upper() != MAGIC:
        raise lines.error(f"not an STP file (the first line must start with {MAGIC})")
    graph: nx.Graph | None = None
    terminals: list[int] | None = None
    while True:
        words = lines.next("SECTION or EOF")
        key = words[0].upper()
        if key == "EOF" and len(words) == 1:
            break
        if key != "SECTION" or len(words) != 2:
            raise lines.error("expected 'SECTION <name>' or 'EOF'")
        name = words[1].upper()
        if name == "GRAPH":
            if graph is not None:
                raise lines.error("a second Graph section")
            graph = _graph_section(lines)
        elif name == "TERMINALS":
            if terminals is not None:
                raise lines.error("a second Terminals section")
            if graph is None:
                raise lines.error("the Terminals section comes before the Graph section")
            terminals = _terminals_section(lines, graph.number_of_nodes())
        else:  # Comment, Coordinates, Presolve, ...: skipped
            _skip_section(lines, words[1])
    if lines.more():
        raise lines.error("text after EOF")
    if graph is None:
        raise ValueError(f"{source}: no Graph section")
    if terminals is None:
        raise ValueError(f"{source}: no Terminals section")
    return SteinerInstance(graph, terminals)


def _skip_section(lines: _Lines, name: str) -> None:
    """Skip to the END of a section this reader does not read."""
    while True:
        key = lines.next(f"END of section {name}")[0].upper()
        if key == "END":
            return
        if key == "SECTION":
            raise lines.error(f"section {name} has no END before this line")


def _count(lines: _Lines, keyword: str) -> int:
    """The line ``<keyword> <count>`` (a non-negative integer)."""
    words = lines.next(f"'{keyword} <count>'")
    if len(words) != 2 or words[0].upper() != keyword.upper():
        raise lines.error(f"expected '{keyword} <count>'")
    count = _integer(lines, words[1], f"{keyword} count")
    if count < 0:
        raise lines.error(f"negative {keyword} count")
    return count


def _integer(lines: _Lines, word: str, what: str) -> int:
    try:
        return int(word)
    except ValueError:
        raise lines.error(f"{what} is not an integer") from None


def _vertex(lines: _Lines, word: str, n: int) -> int:
    v = _integer(lines, word, "vertex")
    if not 1 <= v <= n:
        raise lines.error(f"vertex {v} is not in 1..{n}")
    return v


def _weight(lines: _Lines, word: str) -> int | float:
    try:
        w: int | float = int(word)
    except ValueError:
        try:
            w = float(word)
        except ValueError:
            raise lines.error("the weight is not a number") from None
    if not math.isfinite(w) or w < 0:
        raise lines.error("the weight must be finite and non-negative")
    return w


def _graph_section(lines: _Lines) -> nx.Graph:
    """``Nodes n``, ``Edges m``, ``m`` edge lines, ``END``."""
    n = _count(lines, "Nodes")
    m = _count(lines, "Edges")
    graph = nx.Graph()
    graph.add_nodes_from(range(1, n + 1))
    for _ in range(m):
        words = lines.next("an edge line 'E u v w'")
        if words[0].upper() != "E" or len(words) != 4:
            raise lines.error(f"expected an edge line 'E u v w' ({m} edges declared)")
        u, v = _vertex(lines, words[1], n), _vertex(lines, words[2], n)
        w = _weight(lines, words[3])
        if u == v:
            raise lines.error("a self-loop")
        if graph.has_edge(u, v):
            raise lines.error(f"edge {{{u}, {v}}} appears twice")
        graph.add_edge(u, v, weight=w)
    if [w.upper() for w in lines.next("END of the Graph section")] != ["END"]:
        raise lines.error(f"expected END after {m} edges")
    return graph


def _terminals_section(lines: _Lines, n: int) -> list[int]:
    """``Terminals k``, ``k`` terminal lines, ``END``."""
    k = _count(lines, "Terminals")
    terminals: list[int] = []
    seen: set[int] = set()
    for _ in range(k):
        words = lines.next("a terminal line 'T v'")
        if words[0].upper() != "T" or len(words) != 2:
            raise lines.error(f"expected a terminal line 'T v' ({k} terminals declared)")
        v = _vertex(lines, words[1], n)
        if v in seen:
            raise lines.error(f"terminal {v} appears twice")
        seen.add(v)
        terminals.append(v)
    if [w.upper() for w in lines.next("END of the Terminals section")] != ["END"]:
        raise lines.error(f"expected END after {k} terminals")
    return terminals
