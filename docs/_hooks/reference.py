"""MkDocs hook: add the reference pages generated from the code (tether.reference).

The command line, the scenario keys, the summary keys, the Parquet columns and the API
pages are written when the site is built, never by hand, so they cannot drift from the
product.
"""

from __future__ import annotations

from typing import Any

from mkdocs.structure.files import File, Files

from tether.reference.api import api_nav
from tether.reference.pages import reference_pages

API_INDEX = "reference/api/index.md"


def _with_api(nav: Any) -> Any:
    """The navigation with the API index's entry expanded into every API page."""
    if isinstance(nav, list):
        return [_with_api(item) for item in nav]
    if isinstance(nav, dict):
        return {k: api_nav() if v == API_INDEX else _with_api(v) for k, v in nav.items()}
    return nav


def on_config(config: Any) -> Any:
    config["nav"] = _with_api(config["nav"])
    return config


def on_files(files: Files, config: Any) -> Files:
    for path, text in reference_pages().items():
        files.append(File.generated(config, path, content=text))
    return files
