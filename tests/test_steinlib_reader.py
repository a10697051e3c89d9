"""The STP reader (:mod:`tether.graph.steinlib`): what it reads, and what it refuses."""

from __future__ import annotations

from pathlib import Path

import pytest

from tether.graph.steinlib import parse_stp, read_stp

SMALL = """33D32945 STP File, STP Format Version 1.0

SECTION Comment
Name    "small"
Remark  "SECTION Graph in a comment is not a section"
END

SECTION Coordinates
DD 1 0 0
END

section graph
Nodes 5
Edges 4
E 1 2 3
e 2 3 0
E 5 3 2.5
E 3 4 10
END

SECTION Terminals
Terminals 3
T 4
T 1
T 5
END

EOF
"""


def test_reads_the_graph_and_terminals() -> None:
    graph, terminals = parse_stp(SMALL)
    assert sorted(graph.nodes) == [1, 2, 3, 4, 5]
    assert {frozenset(e): w for *e, w in graph.edges(data="weight")} == {
        frozenset({1, 2}): 3,
        frozenset({2, 3}): 0,
        frozenset({3, 5}): 2.5,
        frozenset({3, 4}): 10,
    }
    assert isinstance(graph.edges[1, 2]["weight"], int)
    assert terminals == [4, 1, 5]  # the file's order


def test_read_stp_reads_a_file(tmp_path: Path) -> None:
    path = tmp_path / "small.stp"
    path.write_text(SMALL)
    graph, terminals = read_stp(path)
    assert graph.number_of_edges() == 4 and terminals == [4, 1, 5]


def test_isolated_vertices_are_kept() -> None:
    graph, _ = parse_stp(SMALL.replace("Nodes 5", "Nodes 7"))
    assert graph.number_of_nodes() == 7 and graph.degree(7) == 0


def _line_of(text: str, needle: str) -> int:
    """The number of the last line holding ``needle``."""
    return max(k for k, line in enumerate(text.splitlines(), 1) if needle in line)


@pytest.mark.parametrize(
    ("old", "new", "message", "below"),
    [
        ("33D32945 STP File", "STP File", "not an STP file", 0),
        ("Nodes 5\n", "Nodes 5\nOptimal 15\n", "expected 'Edges <count>'", 0),
        ("E 1 2 3", "Optimal 15", "expected an edge line", 0),
        ("E 1 2 3", "A 1 2 3", "expected an edge line", 0),
        ("E 1 2 3", "E 1 2", "expected an edge line", 0),
        ("E 1 2 3", "E 0 2 3", "vertex 0 is not in 1..5", 0),
        ("E 1 2 3", "E 1 6 3", "vertex 6 is not in 1..5", 0),
        ("E 1 2 3", "E 1 x 3", "vertex is not an integer", 0),
        ("E 1 2 3", "E 1 2 -3", "non-negative", 0),
        ("E 1 2 3", "E 1 2 nan", "finite", 0),
        ("E 1 2 3", "E 1 2 three", "not a number", 0),
        ("E 1 2 3", "E 2 2 3", "self-loop", 0),
        ("E 3 4 10", "E 3 2 10", "appears twice", 0),
        ("Edges 4", "Edges 5", "expected an edge line", 5),  # at the END line
        ("Edges 4", "Edges 3", "expected END after 3 edges", 4),  # at the 4th edge
        ("Nodes 5", "Nodes -1", "negative Nodes count", 0),
        ("Terminals 3", "Terminals 4", "expected a terminal line", 4),
        ("Terminals 3", "Terminals 2", "expected END after 2 terminals", 3),
        ("T 1", "T 4", "terminal 4 appears twice", 0),
        ("T 1", "T 9", "vertex 9 is not in 1..5", 0),
        ("T 1", "Root 1", "expected a terminal line", 0),
        ("DD 1 0 0\nEND", "DD 1 0 0\n", "section Coordinates has no END", 3),
        ("EOF", "SECTION", "expected 'SECTION <name>' or 'EOF'", 0),
        ("EOF\n", "EOF\nE 1 2 3\n", "text after EOF", 0),
    ],
)
def test_malformed_input_names_the_line(old: str, new: str, message: str, below: int) -> None:
    """The message starts with ``file:line:``, ``below`` lines under the changed line."""
    assert old in SMALL
    text = SMALL.replace(old, new, 1)
    line = _line_of(text, new.strip().splitlines()[-1]) + below
    with pytest.raises(ValueError, match=message) as err:
        parse_stp(text, source="x.stp")
    assert str(err.value).startswith(f"x.stp:{line}: ")
    assert str(err.value).endswith(repr(text.splitlines()[line - 1].strip()))


@pytest.mark.parametrize(
    ("text", "message"),
    [
        (SMALL.replace("EOF\n", ""), "the file ends where SECTION or EOF was expected"),
        (SMALL.split("T 5\n")[0] + "T 5\n", "ends where END of the Terminals section"),
        (SMALL.split("SECTION Terminals")[0] + "EOF\n", "no Terminals section"),
        (SMALL.split("SECTION Coordinates")[0] + "EOF\n", "no Graph section"),
        ("", "ends where the STP header was expected"),
    ],
)
def test_truncated_or_incomplete_files(text: str, message: str) -> None:
    with pytest.raises(ValueError, match=message) as err:
        parse_stp(text, source="x.stp")
    assert str(err.value).startswith("x.stp")


def test_sections_in_the_wrong_order_or_twice() -> None:
    head, rest = SMALL.split("section graph")
    graph_part, terminal_part = rest.split("SECTION Terminals")
    swapped = head + "SECTION Terminals" + terminal_part.replace("EOF\n", "")
    with pytest.raises(ValueError, match="comes before the Graph section"):
        parse_stp(swapped + "section graph" + graph_part + "EOF\n")
    twice = SMALL.replace("EOF\n", "SECTION Graph" + graph_part + "EOF\n")
    with pytest.raises(ValueError, match="a second Graph section"):
        parse_stp(twice)
