"""The scenario fuzzer: mutated built-in scenarios and campaigns through ``validate`` and ``run``.

A case is a built-in scenario or paper campaign (its YAML as written) with one to three
mutations drawn by hypothesis: a key deleted, a value of the wrong type, an extreme
number, unicode text, deep nesting, a shared value (YAML aliases, up to an alias bomb),
and, in the YAML text, a tag or a key given twice. Each case goes through ``tether
validate`` and then ``tether run`` (in this process, a few steps, no figures, numpy
paths), each bounded in time. The property: either both refuse with the same single
``error:`` line and exit code 2, or both succeed; never a traceback, an exit code 1, a
hang, or a disagreement. ``tests/test_fuzz_scenarios.py`` runs a few dozen cases in the
suite; ``benchmarks/fuzz_scenarios.py`` runs thousands and prints the counts.
"""

from __future__ import annotations

import contextlib
import copy
import io
import math
import os
import shutil
import signal
import tempfile
from collections import Counter
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml
from hypothesis import strategies as st

from tether import cli, jit
from tether.config import builtin_scenarios, paper_campaigns, read_scenario_data

#: the steps a fuzzed run simulates (``--set sim.max_steps=...``)
STEPS = 2
#: the longest either command of a case may take before it counts as a hang (seconds)
HANG_S = 120.0
#: the memory a fuzzed run may ask for (``TETHER_MEMORY_LIMIT_GB``)
MEMORY_GB = "2"

BASES = builtin_scenarios() + paper_campaigns()

WRONG_TYPES = ["text", "", [], {}, None, True, False, [1, "x"], {"a": 1}, [[1, 2], [3]], "1e3"]
EXTREME = [0, -1, -0.0, 1, 1e308, -1e308, math.nan, math.inf, -math.inf, 2**63, 2**64,
           -(2**63) - 1, 1e-308, 5e-324, 10**30, 1e7, 1_000_000, 0.5, 3]  # fmt: skip
TAGS = ["!!python/object/apply:os.system ['true']", "!!python/name:sys.exit", "!!binary aGk=",
        "!!set {a: null}", "!!timestamp 2001-12-14", "!!float '1e3'", "!!str 5", "!custom x",
        "!!omap [{a: 1}]", "!!int '0x10'"]  # fmt: skip
_TAG_SENTINEL = "TETHER-FUZZ-TAG"


def _paths(node: Any, prefix: tuple = (), limit: int = 400) -> list[tuple]:
    """Key paths in ``node`` (mapping keys, the first list indices), parents first; at
    most 8 levels deep and ``limit`` paths (an alias bomb has billions)."""
    out: list[tuple] = []
    if len(prefix) >= 8:
        return out
    items = node.items() if isinstance(node, dict) else enumerate(node[:6]) \
        if isinstance(node, list) else []  # fmt: skip
    for key, value in items:
        if len(out) >= limit:
            break
        out.append((*prefix, key))
        out.extend(_paths(value, (*prefix, key), limit - len(out)))
    return out


def _loops(node: Any, active: set[int] | None = None, done: set[int] | None = None) -> bool:
    """``node`` contains itself (through shared values)."""
    active = set() if active is None else active
    done = set() if done is None else done
    if not isinstance(node, dict | list) or id(node) in done:
        return False
    if id(node) in active:
        return True
    active.add(id(node))
    children = node.values() if isinstance(node, dict) else node
    found = any(_loops(child, active, done) for child in children)
    active.discard(id(node))
    done.add(id(node))
    return found


def _parent(data: Any, path: tuple) -> tuple[Any, Any]:
    node = data
    for part in path[:-1]:
        node = node[part]
    return node, path[-1]


def _deep(depth: int) -> Any:
    value: Any = 1.0
    for k in range(depth):
        value = [value] if k % 2 else {"x": value}
    return value


def _bomb(width: int, levels: int) -> list:
    value: list = ["x"] * width
    for _ in range(levels):
        value = [value] * width
    return value


@st.composite
def _unicode(draw: st.DrawFn) -> str:
    return draw(st.one_of(
        st.text(min_size=1, max_size=30),
        st.sampled_from(["😀" * 100, "\u202eevil", "a\u0000b", "名前", "é" * 300, "\n\t",
                         "../../x", "<!--<script>", "x" * 5000, "\ud7ff", "NaN", "~"]),
    ))  # fmt: skip


@st.composite
def mutations(draw: st.DrawFn, data: dict) -> tuple[dict, list[str], list[str]]:
    """``data`` mutated one to three times; the mutated data, the text edits, descriptions."""
    data = copy.deepcopy(data)
    text_edits: list[str] = []
    described: list[str] = []
    for _ in range(draw(st.integers(1, 3))):
        paths = _paths(data)
        if not paths:
            break
        path = draw(st.sampled_from(paths))
        node, key = _parent(data, path)
        kind = draw(st.sampled_from(["delete", "type", "number", "unicode", "nest", "alias",
                                     "bomb", "tag", "duplicate", "key"]))  # fmt: skip
        where = ".".join(map(str, path))
        if kind == "delete":
            if isinstance(node, dict):
                del node[key]
            else:
                node.pop(key)
        elif kind == "type":
            node[key] = copy.deepcopy(draw(st.sampled_from(WRONG_TYPES)))
        elif kind == "number":
            node[key] = draw(st.sampled_from(EXTREME))
        elif kind == "unicode":
            node[key] = draw(_unicode())
        elif kind == "nest":
            node[key] = _deep(draw(st.integers(10, 150)))
        elif kind == "alias":  # the same object twice: PyYAML writes an anchor and an alias
            other = draw(st.sampled_from(paths))
            if other == path[: len(other)]:
                continue  # a value inside itself: a loop, which YAML cannot write
            other_node, other_key = _parent(data, other)
            try:
                before, node[key] = node[key], other_node[other_key]
            except (KeyError, IndexError, TypeError):
                continue
            if _loops(data):  # through values shared by earlier aliases
                node[key] = before
                continue
        elif kind == "bomb":
            node[key] = _bomb(draw(st.integers(2, 12)), draw(st.integers(1, 9)))
        elif kind == "tag":
            node[key] = _TAG_SENTINEL
            text_edits.append(f"tag:{draw(st.sampled_from(TAGS))}")
        elif kind == "duplicate":
            text_edits.append(f"duplicate:{draw(st.integers(0, 10_000))}")
        elif kind == "key" and isinstance(node, dict):
            node[draw(_unicode())] = draw(st.sampled_from(EXTREME + WRONG_TYPES))
        described.append(f"{kind} {where}")
    return data, text_edits, described


def render(data: dict, text_edits: list[str]) -> str:
    """The case's YAML text: ``data`` dumped, then the tags and repeated keys put in."""
    try:
        text = yaml.safe_dump(data, allow_unicode=True, sort_keys=False)
    except (yaml.YAMLError, RecursionError, UnicodeEncodeError):
        text = yaml.safe_dump(data, sort_keys=False, width=10**9)
    for edit in text_edits:
        kind, _, arg = edit.partition(":")
        if kind == "tag":
            text = text.replace(_TAG_SENTINEL, arg, 1)
        elif kind == "duplicate":
            lines = text.splitlines()
            keyed = [k for k, line in enumerate(lines) if ": " in line or line.endswith(":")]
            if keyed:
                k = keyed[int(arg) % len(keyed)]
                lines.insert(k + 1, lines[k])  # the same key again (or a YAML error)
            text = "\n".join(lines) + "\n"
    return text.replace(_TAG_SENTINEL, "x")


@st.composite
def cases(draw: st.DrawFn, bases: list[str] | None = None) -> tuple[str, str, list[str]]:
    """A fuzz case: the base's name, the case's YAML text, what was mutated."""
    name = draw(st.sampled_from(bases or BASES))
    data, _, _ = read_scenario_data(name)
    mutated, edits, described = draw(mutations(data))
    return name, render(mutated, edits), described


class Hang(BaseException):
    """A command ran longer than :data:`HANG_S` (not an Exception: nothing swallows it)."""


@dataclass
class Outcome:
    code: int | None
    out: str
    err: str


def _alarm(signum: int, frame: Any) -> None:
    raise Hang


def tether(*args: str, timeout_s: float = HANG_S) -> Outcome:
    """``tether ARGS`` in this process: its exit code (None: a hang) and output."""
    out, err = io.StringIO(), io.StringIO()
    previous = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, timeout_s)
    code: int | None = 0
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            cli.main(list(args))
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    except Hang:
        code = None
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, previous)
    return Outcome(code, out.getvalue(), err.getvalue())


def _one_error_line(o: Outcome) -> bool:
    lines = o.err.strip().splitlines()
    return len(lines) == 1 and lines[0].startswith("error: ") and "internal error" not in lines[0]


def classify(validate: Outcome, run: Outcome | None) -> str:
    """``refused``, ``ran``, or the broken promise: ``hang``, ``traceback``, ``exit-1``,
    ``not-one-line`` or ``disagree`` (validate and run differ)."""
    both = [validate] if run is None else [validate, run]
    if any(o.code is None for o in both):
        return "hang"
    if any("Traceback" in o.err for o in both):
        return "traceback"
    if any(o.code not in (0, 2) for o in both):
        return "exit-1"
    if any(o.code == 2 and not _one_error_line(o) for o in both):
        return "not-one-line"
    if run is None or validate.code != run.code:
        return "disagree"
    if validate.code == 2:
        return "refused" if validate.err.strip() == run.err.strip() else "disagree"
    return "ran"


@contextlib.contextmanager
def fuzz_environment(root: Path) -> Any:
    """Numpy paths, a small memory allowance, the checkout as working directory."""
    saved = {k: os.environ.get(k) for k in ("TETHER_MEMORY_LIMIT_GB", "MPLBACKEND")}
    os.environ["TETHER_MEMORY_LIMIT_GB"] = MEMORY_GB
    os.environ["MPLBACKEND"] = "Agg"
    cwd = os.getcwd()
    os.chdir(root)  # the campaigns name ../shared/maps from the checkout
    try:
        with jit.using(False):
            yield
    finally:
        os.chdir(cwd)
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value


def check_case(text: str, work: Path) -> tuple[str, Outcome, Outcome | None]:
    """Run one case's YAML text through ``validate`` then ``run``; its class and outputs."""
    folder = Path(tempfile.mkdtemp(dir=work, prefix="case-"))
    try:
        path = folder / "case.yaml"
        path.write_text(text, encoding="utf-8", errors="surrogatepass")
        steps = ("--set", f"sim.max_steps={STEPS}")
        validate = tether("validate", str(path), *steps)
        run = None
        if validate.code is not None:
            run = tether("run", str(path), *steps, "--no-figures", "--out", str(folder / "out"))
        return classify(validate, run), validate, run
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def tally(counts: Counter) -> dict[str, int]:
    keys = ["cases", "refused", "ran", "traceback", "exit-1", "hang", "not-one-line", "disagree"]
    return {k: counts.get(k, 0) for k in keys}
