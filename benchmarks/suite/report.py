"""The suite's results file and the Markdown tables made from it.

``benchmarks/results/<machine>.json`` holds, per row, the lines (goal, peer, ours,
ratio, warm-up), the details and when and under what load it ran. Pages show tables
made from it between markers::

    <!-- suite:TABLE benchmarks/results/MACHINE.json -->
    | ... the table, rewritten by ``python benchmarks/run.py --docs`` ... |
    <!-- /suite -->

``TABLE`` names a function of :data:`TABLES`; ``tests/test_benchmark_suite.py`` checks
that every marked table is what the named results file gives.
"""

from __future__ import annotations

import json
import os
import platform
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

from suite.core import ROOT

RESULTS = ROOT / "benchmarks" / "results"
#: pages whose marked tables ``--docs`` rewrites
PAGES = (
    "docs/performance.md",
    "docs/explanation/silent.md",
    "docs/explanation/continuous.md",
    "docs/explanation/paths.md",
    "docs/explanation/recurrent_planning.md",
    "docs/how-to/viewing.md",
    "docs/how-to/experiments.md",
)
MARKER = re.compile(
    r"(<!-- suite:(?P<table>[\w-]+) (?P<file>\S+) -->\n)(?P<body>.*?)(<!-- /suite -->)",
    re.DOTALL,
)


def machine_name() -> str:
    """A file name for this machine: CPU model and core count, e.g.
    ``intel-xeon-platinum-8481c-2cores``."""
    cpu = platform.processor() or platform.machine()
    try:
        with open("/proc/cpuinfo") as fh:
            cpu = next((ln.split(":", 1)[1] for ln in fh if ln.startswith("model name")), cpu)
    except OSError:
        pass
    cpu = re.sub(r"\((r|tm)\)|\bcpu\b|@.*$|\bprocessor\b|\d+-core", " ", cpu.lower())
    slug = "-".join(re.findall(r"[a-z0-9]+", cpu))
    return f"{slug or 'unknown'}-{os.cpu_count()}cores"


def load(path: Path) -> dict[str, Any]:
    """The results file (an empty one if it does not exist yet)."""
    if path.exists():
        return json.loads(path.read_text())
    return {"rows": {}}


def save(path: Path, doc: dict[str, Any]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".json.tmp")
    tmp.write_text(json.dumps(doc, indent=1, sort_keys=False, default=float) + "\n")
    tmp.replace(path)


# --- numbers as the tables show them ---------------------------------------------------


def num(value: float | None, digits: int = 3) -> str:
    """``digits`` significant digits, thousands separated; ``-`` for ``None``."""
    if value is None:
        return "-"
    if value == 0:
        return "0"
    mag = abs(value)
    if mag >= 10 ** (digits - 1):
        return f"{value:,.0f}"
    decimals = max(0, digits - 1 - int(f"{mag:e}".split("e")[1]))
    return f"{value:,.{decimals}f}"


def with_unit(value: float | None, unit: str) -> str:
    if value is None:
        return "-"
    return f"{num(value)}x" if unit == "x" else f"{num(value)} {unit}"


def seconds(value: float | None) -> str:
    """A duration in s from 1 s up, else in ms; ``-`` for ``None``."""
    if value is None:
        return "-"
    return f"{num(value)} s" if value >= 1 else f"{num(1e3 * value)} ms"


def table_summary(doc: dict) -> str:
    """Every line of every row: goal, peer, ours, peer's, ratio, met, warm-up."""
    head = "| row | what | goal | ours | peer (same run) | peer's | ratio | met | warm-up |"
    out = [head, "| --- | --- | --- | --- | --- | --- | --- | --- | --- |"]
    for name, rec in doc["rows"].items():
        if rec.get("skipped"):
            out.append(f"| `{name}` | {rec['title']}: not measured ({rec['skipped']}) "
                       "| - | - | - | - | - | - | - |")  # fmt: skip
        for ln in rec["lines"]:
            met = {True: "yes", False: "**no**", None: "-"}[ln["met"]]
            worst = ln["extra"].get("worst_ratio")
            ours = with_unit(ln["ours"], ln["unit"])
            if worst is not None:
                ours += f" (worst {num(worst)}x)"
            peer_value = with_unit(ln["peer_value"], ln["unit"])
            ratio = "-" if ln["ratio"] is None else f"{num(ln['ratio'])}x"
            out.append(
                f"| `{name}` | {ln['label']} | {ln['goal']} | {ours} | {ln['peer']} | "
                f"{peer_value} | {ratio} | {met} | {seconds(ln['warmup_s'])} |"
            )
    return "\n".join(out)


def table_machine(doc: dict) -> str:
    """The machine, the versions and the load of the run."""
    m = doc.get("machine", {})
    loads = [rec.get("load_average") for rec in doc["rows"].values() if rec.get("load_average")]
    lo = min(x[0] for x in loads) if loads else None
    hi = max(x[1] for x in loads) if loads else None
    return "\n".join(
        [
            "| machine | cores | Python | numpy | scipy | numba | networkx | load (1 min) |",
            "| --- | --- | --- | --- | --- | --- | --- | --- |",
            f"| {m.get('cpu', '-')} | {m.get('cpu_count', '-')} | {m.get('python', '-')} | "
            f"{m.get('numpy', '-')} | {m.get('scipy', '-')} | {m.get('numba', '-')} | "
            f"{m.get('networkx', '-')} | {num(lo, 2)}-{num(hi, 2)} |",
        ]
    )


def _detail(doc: dict, row: str, key: str) -> list[dict]:
    return doc["rows"].get(row, {}).get("details", {}).get(key, [])


def table_steinlib(doc: dict) -> str:
    """Per SteinLib instance: size, optimum, warm and cold times against mehlhorn."""
    out = [
        "| instance | vertices | edges | terminals | optimum = ours | warm: ours / mehlhorn (ms) "
        "| ratio | cold: ours / mehlhorn (ms) | ratio |",
        "| --- | --- | --- | --- | --- | --- | --- | --- | --- |",
    ]
    for r in _detail(doc, "steiner_steinlib", "instances"):
        out.append(
            f"| {r['instance']} | {r['vertices']} | {r['edges']} | {r['terminals']} | "
            f"{r['cost']:g} | {num(1e3 * r['exact_s'])} / {num(1e3 * r['mehlhorn_s'])} | "
            f"{num(r['ratio'])}x | {num(1e3 * r['cold_exact_s'])} / "
            f"{num(1e3 * r['cold_mehlhorn_s'])} | {num(r['cold_ratio'])}x |"
        )
    return "\n".join(out)


def table_steinlib_scaling(doc: dict) -> str:
    """Per set-B instance up to 19 terminals: the cost and one solve's time."""
    out = [
        "| instance | vertices | edges | terminals | optimum | `steiner_tree` cost | "
        "compiled (s) | reference (s) |",
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |",
    ]
    for r in _detail(doc, "steiner_scaling", "instances"):
        ref = "not run" if r["reference_s"] is None else num(r["reference_s"])
        out.append(
            f"| {r['instance']} | {r['vertices']} | {r['edges']} | {r['terminals']} | "
            f"{r['optimum']} | {r['cost']:g} | {num(r['compiled_s'])} | {ref} |"
        )
    return "\n".join(out)


TABLES: dict[str, Callable[[dict], str]] = {
    "steinlib_scaling": table_steinlib_scaling,
    "summary": table_summary,
    "machine": table_machine,
    "steinlib": table_steinlib,
}


def register_table(name: str) -> Callable:
    """Add a table function (rows modules register their detail tables here)."""

    def add(fn: Callable[[dict], str]) -> Callable[[dict], str]:
        TABLES[name] = fn
        return fn

    return add


def render_page(text: str, results: Callable[[str], dict]) -> str:
    """``text`` with every marked table re-made from its results file."""

    def fill(match: re.Match) -> str:
        doc = results(match.group("file"))
        body = TABLES[match.group("table")](doc)
        return f"{match.group(1)}{body}\n{match.group(5)}"

    return MARKER.sub(fill, text)


def marked_tables(text: str) -> list[tuple[str, str, str]]:
    """``(table, results file, body)`` of every marked table of a page."""
    return [(m.group("table"), m.group("file"), m.group("body")) for m in MARKER.finditer(text)]


def rewrite_pages(results_file: Path) -> list[str]:
    """Point every marked table of :data:`PAGES` at ``results_file`` and re-make it."""
    rel = results_file.resolve().relative_to(ROOT).as_posix()
    doc = load(results_file)
    changed = []
    for page in PAGES:
        path = ROOT / page
        text = path.read_text()
        pointed = re.sub(r"(<!-- suite:[\w-]+ )\S+( -->)", rf"\g<1>{rel}\g<2>", text)
        new = render_page(pointed, lambda _f: doc)
        if new != text:
            path.write_text(new)
            changed.append(page)
    return changed
