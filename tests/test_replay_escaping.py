"""The replay page escapes data for the script context it lives in.

A scenario name holding ``<!--<script>`` made the browser read the rest of the page as
data (the page was empty); ``</script>`` would end the data element. Data now reaches the
page as JSON without ``<``, ``>`` or ``&``, so no name can change how the page is parsed.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from _viewing_helpers import make_run_folder
from test_replay_browser import Page, browser  # noqa: F401 - the real Chromium fixture
from tether.viewing.replay import render_html, script_json, write_replay

NASTY = [
    "<!--<script>",
    "</script><script>alert(1)</script>",
    "<!--",
    "<script",
    "</SCRIPT >",
    "a & b > c",
    "\u2028\u2029",
    "<!-- <script> </script> -->",
]


def meta_element(page: str) -> str:
    """The text of the page's meta element, as the HTML parser's script state ends it."""
    start = page.index('<script type="application/json" id="tether-meta">')
    start = page.index(">", start) + 1
    return page[start : page.index("</script", start)]


@settings(max_examples=200, deadline=None)
@given(st.text(alphabet=st.sampled_from(list("<!-/>&sScriptRIPT \u2028'\"\\")), max_size=40))
def test_any_name_is_the_same_json_and_holds_no_markup(name):
    text = script_json({"name": name})
    assert not re.search(r"[<>&]", text)
    assert json.loads(text) == {"name": name}


@pytest.mark.parametrize("name", NASTY)
def test_the_meta_element_is_exactly_the_data(name):
    page = render_html({"name": name, "notes": [name]}, "AAAA")
    assert json.loads(meta_element(page)) == {"name": name, "notes": [name]}
    assert page.count("</script>") == page.count("<script")  # every element closes


def replay_named(tmp_path: Path, name: str) -> Path:
    run_dir = tmp_path / "run"
    make_run_folder(run_dir, n_steps=5)
    summary = json.loads((run_dir / "summary.json").read_text())
    summary["scenario"] = name
    (run_dir / "summary.json").write_text(json.dumps(summary))
    return write_replay(run_dir).path


@pytest.mark.parametrize("name", ["<!--<script>", "</script><script>window.pwned=1</script>"])
def test_the_page_draws_in_a_browser_whatever_the_name(browser, tmp_path, name):  # noqa: F811
    page = Page(browser, replay_named(tmp_path, name))
    assert page.js("document.getElementById('title').textContent").startswith(name)
    assert page.js("window.pwned === undefined")
    assert len(page.markers()) == 8  # the robots are drawn: the page was not blanked
    assert page.errors == []
