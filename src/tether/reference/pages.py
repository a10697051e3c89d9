"""The generated reference pages, as Markdown: ``{path under docs/: text}``.

:func:`reference_pages` is what the site's build hook adds to the documentation; every
number and name in them is read from the code at build time.
"""

from __future__ import annotations

from collections.abc import Iterable

from pydantic import BaseModel

from tether.reference.api import api_pages
from tether.reference.cli import commands, main_help
from tether.reference.outputs import (
    CORE_EVENTS,
    CORE_LINKS,
    CORE_ROBOTS,
    CORE_STEPS,
    CORE_SUMMARY,
    EVENTS,
    Output,
)
from tether.reference.schema import KeyDoc, unit_of, value_text
from tether.reference.sections import Section, scenario_sections
from tether.reference.strategy_outputs import STRATEGY_OUTPUTS

_GENERATED = (
    "<!-- generated from the code by tether.reference when the site is built; "
    "edit the code, not this page -->\n\n"
)


def cell(text: str) -> str:
    """Text fit for a Markdown table cell: reST literals as Markdown, pipes escaped, and
    ``<`` / ``>`` outside code spans as entities (not HTML tags)."""
    parts = " ".join(str(text).replace("``", "`").replace("|", "\\|").split()).split("`")
    for k in range(0, len(parts), 2):  # outside code spans
        parts[k] = parts[k].replace("<", "&lt;").replace(">", "&gt;")
    return "`".join(parts)


def code(text: str) -> str:
    return f"`{text}`" if text else ""


def table(header: Iterable[str], rows: Iterable[Iterable[str]]) -> str:
    head = list(header)
    lines = ["| " + " | ".join(head) + " |", "|" + " --- |" * len(head)]
    lines += ["| " + " | ".join(cell(c) for c in row) + " |" for row in rows]
    return "\n".join(lines) + "\n"


def _paragraphs(help_text: str) -> str:
    out = []
    for para in help_text.strip().split("\n\n"):
        text = " ".join(para.split())
        if text.startswith("Example: "):
            out.append(f"```bash\n{text.removeprefix('Example: ')}\n```")
        elif text:
            out.append(text)
    return "\n\n".join(out) + "\n"


def cli_page() -> str:
    parts = [
        "# Command line\n\n",
        _GENERATED,
        f"{cell(main_help())}\n\n`tether` alone, or `-h` / `--help` after any command, prints "
        "its help; `tether --version` prints the version and the commit; `python -m tether` "
        "is the same command. Exit codes: [errors and exit codes](errors.md).\n",
    ]
    for cmd in commands():
        parts.append(f"\n## `tether {cmd.name}`\n\n```\n{cmd.usage}\n```\n\n")
        parts.append(_paragraphs(cmd.help) + "\n")
        rows = [
            [code(o.names), o.type, code(o.default) if o.default not in ("required", "off") else
             o.default, o.range, o.help]
            for o in cmd.options
        ]  # fmt: skip
        parts.append(table(["argument / option", "type", "default", "range", "what"], rows))
    return "".join(parts)


def _key_rows(rows: list[KeyDoc]) -> list[list[str]]:
    return [
        [code(r.key), r.type, r.unit, code(r.default) if r.default != "required" else r.default,
         r.range, r.description]
        for r in rows
    ]  # fmt: skip


def _flat(data: dict, prefix: str = "") -> dict[str, object]:
    out: dict[str, object] = {}
    for k, v in data.items():
        key = f"{prefix}.{k}" if prefix else k
        out.update(_flat(v, key) if isinstance(v, dict) else {key: v})
    return out


def preset_table(model: type[BaseModel], prefix: str) -> str:
    """The defaults each ``preset`` sets, where presets differ (Tables 2 and 3)."""
    choices = model.model_fields["preset"].annotation.__args__  # type: ignore[union-attr]
    values = {p: _flat(model.model_validate({"preset": p}).model_dump()) for p in choices}
    keys = [k for k in values[choices[0]]
            if k != "preset" and len({repr(values[p][k]) for p in choices}) > 1]  # fmt: skip
    rows = [[code(f"{prefix}.{k}"), *(code(value_text(values[p][k])) for p in choices)]
            for k in keys]  # fmt: skip
    return (
        "\nThe defaults above are the `outdoor` column; `preset` sets these, and a key given "
        "explicitly overrides its preset:\n\n" + table(["key", *choices], rows)
    )


def _section(section: Section) -> str:
    text = f"\n## {section.title}\n\n"
    if section.intro:
        text += f"{cell(section.intro)}\n\n"
    text += table(["key", "type", "unit", "default", "range", "description"],
                  _key_rows(section.rows))  # fmt: skip
    model = section.model
    if model is not None and "preset" in model.model_fields and section.rows:
        text += preset_table(model, "strategy.params")
    return text


def scenario_page() -> str:
    intro = (
        "# Scenario keys\n\n" + _GENERATED + "A scenario is a YAML file validated before "
        "anything runs: an unknown key, a wrong type or a value out of its range is one "
        "line naming the file, the key and the fix (exit code 2). Keys are dotted paths as "
        "`--set` takes them (`--set strategy.params.d0_m=5`); `a[].b` is the key `b` of "
        "each item of the list `a`. A unit comes from the key's name (`_m` metres, `_s` "
        "seconds, `_mps` metres per second, `_deg` degrees, `_n` newtons, ...); a key "
        "without one is a count, a ratio or a choice. The `sweep:` block's grammar: "
        "[running experiments](../how-to/experiments.md#the-sweep-grammar).\n"
    )
    return intro + "".join(_section(s) for s in scenario_sections())


def _output_rows(outputs: dict[str, Output]) -> list[list[str]]:
    return [[code(k), unit_of(k), o.when or "always", o.description] for k, o in outputs.items()]


_OUTPUT_HEADER = ["key", "unit", "written", "description"]


def summary_page() -> str:
    parts = [
        "# Summary keys\n\n",
        _GENERATED,
        "`summary.json` holds a run's scalar results; it is written last, so a run folder "
        "holding it is complete ([run folder](run-folder.md)). Every run has the keys of the "
        "first table; each strategy adds its own. A strategy's key that has a core key's "
        "name is stored as `strategy_<name>`. Sweeps copy every scalar key into "
        "`sweep.parquet`.\n\n## Every run\n\n",
        table(_OUTPUT_HEADER, _output_rows(CORE_SUMMARY)),
    ]
    for name, outputs in STRATEGY_OUTPUTS.items():
        parts.append(f"\n## Strategy `{name}`\n\n")
        parts.append(table(_OUTPUT_HEADER, _output_rows(outputs.summary)))
    return "".join(parts)


def _columns(title: str, intro: str, core: dict[str, Output], attr: str) -> str:
    text = f"\n## `{title}`\n\n{intro}\n\n" + table(_OUTPUT_HEADER, _output_rows(core))
    for name, outputs in STRATEGY_OUTPUTS.items():
        own = getattr(outputs, attr)
        if own:
            text += f"\nStrategy `{name}` adds:\n\n" + table(_OUTPUT_HEADER, _output_rows(own))
    return text


def tables_page() -> str:
    events = [
        [code(kind), ", ".join(code(s) for s in e.strategies), e.description,
         "; ".join(f"`{f}`: {d}" for f, d in e.fields.items())]
        for kind, e in EVENTS.items()
    ]  # fmt: skip
    return "".join(
        [
            "# Parquet tables and events\n\n",
            _GENERATED,
            "A run folder holds four Parquet tables (read them with pandas, polars or "
            'pyarrow: `pandas.read_parquet("runs/x/steps.parquet")`). Every run has the '
            "core columns; a strategy adds its own.\n",
            _columns("steps.parquet", "One row per step.", CORE_STEPS, "steps"),
            _columns(
                "robots.parquet",
                "One row per recorded step (every `output.record_every`-th) and robot.",
                CORE_ROBOTS,
                "robots",
            ),
            f"\n## `links.parquet`\n\nOne row per recorded step and link of the true "
            f"interaction graph.\n\n{table(_OUTPUT_HEADER, _output_rows(CORE_LINKS))}",
            "\n## `events.parquet`\n\nOne row per event. Every event has `step` and "
            "`kind`; the other columns are those of its kind (empty for the others).\n\n",
            table(_OUTPUT_HEADER, _output_rows(CORE_EVENTS)),
            "\n### Event kinds\n\n",
            table(["kind", "strategies", "what happened", "its columns"], events),
        ]
    )


def reference_pages() -> dict[str, str]:
    """Every generated page: ``{path relative to docs/: Markdown}``."""
    return {
        "reference/cli.md": cli_page(),
        "reference/scenario.md": scenario_page(),
        "reference/summary.md": summary_page(),
        "reference/tables.md": tables_page(),
        **api_pages(),
    }
