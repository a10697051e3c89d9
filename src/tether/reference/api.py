"""The Python API pages: one per top-level module or package, rendered by mkdocstrings.

Every public module of :mod:`tether` is documented from its numpydoc docstrings, except
the compiled kernels (``*_kernels``: numba twins of the numpy code that documents them)
and the ``python -m tether`` entry point.
"""

from __future__ import annotations

import pkgutil

import tether

#: modules shown by their own docstring only, without their members: a member's docstring
#: has a paragraph after its Parameters entries that the numpydoc parser reads as a
#: parameter, which the strict build refuses. Fixing that docstring empties this set.
MODULE_DOCSTRING_ONLY: frozenset[str] = frozenset({"tether.continuous.connectivity.weights"})
_NO_MEMBERS = "\n    options:\n      members: false"


def api_modules() -> list[str]:
    """The documented modules, sorted."""
    names = [m.name for m in pkgutil.walk_packages(tether.__path__, "tether.")]
    return sorted(
        n
        for n in names
        if not n.endswith("_kernels")
        and n != "tether.__main__"
        and not n.startswith("tether.scenarios")
    )


def api_groups() -> dict[str, list[str]]:
    """``{page title: modules}``: a top-level module alone, a package with its modules."""
    groups: dict[str, list[str]] = {"tether": ["tether"]}
    for name in api_modules():
        head = ".".join(name.split(".")[:2])
        groups.setdefault(head, []).append(name)
    return groups


def api_path(group: str) -> str:
    return f"reference/api/{group}.md"


def api_pages() -> dict[str, str]:
    """The index and one page per group."""
    groups = api_groups()
    index = [
        "# Python API\n\n",
        "Generated from the numpydoc docstrings when the site is built. Start with "
        "`tether.runner` (`run`, `build`), `tether.config` (scenarios), `tether.sim` (the "
        "loop and the strategy contract) and `tether.registry` (plug-in points); the "
        "architecture of the packages: [architecture](../../explanation/architecture.md).\n\n",
    ]
    pages: dict[str, str] = {}
    for group, modules in groups.items():
        index.append(f"- [`{group}`]({group}.md)\n")
        body = "".join(
            f"::: {m}{_NO_MEMBERS if m in MODULE_DOCSTRING_ONLY else ''}\n\n" for m in modules
        )
        pages[api_path(group)] = f"# `{group}`\n\n{body}"
    pages["reference/api/index.md"] = "".join(index)
    return pages


def api_nav() -> list[dict[str, str] | str]:
    """The site navigation's entries of the API pages."""
    return ["reference/api/index.md", *({g: api_path(g)} for g in api_groups())]
