"""Every command and option of the ``tether`` command line, read from the typer app."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import typer

from tether.cli import app
from tether.reference.schema import type_name, value_text


@dataclass(frozen=True)
class OptionDoc:
    """One argument or option of a command."""

    names: str
    type: str
    default: str
    range: str
    help: str
    argument: bool


@dataclass(frozen=True)
class CommandDoc:
    """One command: its name, usage line, help paragraphs and options."""

    name: str
    usage: str
    help: str
    options: list[OptionDoc]


def _type(param: Any) -> str:
    descriptor = getattr(param, "type_descriptor", None)  # typer's own parameters
    if descriptor is not None:
        text = type_name(descriptor.annotation)
    else:  # click's
        text = str(getattr(getattr(param, "type", None), "name", "text"))
    return text.removeprefix("list of ") + " (repeatable)" if param.multiple else text


def _range(param: Any) -> str:
    low, high = getattr(param, "min", None), getattr(param, "max", None)
    parts = [f">= {low}"] if low is not None else []
    return ", ".join([*parts, f"<= {high}"] if high is not None else parts)


def _option(param: Any) -> OptionDoc:
    argument = param.param_type_name == "argument"
    names = param.name.upper() if argument else ", ".join([*param.opts, *param.secondary_opts])
    if param.required:
        default = "required"
    elif getattr(param, "is_flag", False) and param.default is False:
        default = "off"
    else:
        default = "" if param.default is None else value_text(param.default)
    return OptionDoc(names, _type(param), default, _range(param), param.help or "", argument)


def _usage(name: str, params: list[Any]) -> str:
    words = ["tether", name]
    for p in params:
        if p.param_type_name == "argument":
            word = p.name.upper() + ("..." if p.nargs == -1 or p.multiple else "")
            words.append(word if p.required else f"[{word}]")
    if any(p.param_type_name == "option" for p in params):
        words.append("[OPTIONS]")
    return " ".join(words)


def commands() -> list[CommandDoc]:
    """Every command of ``tether`` in the order ``tether --help`` lists them."""
    group = typer.main.get_command(app)
    out = []
    for name, command in group.commands.items():  # type: ignore[attr-defined]
        params = [p for p in command.params if not getattr(p, "hidden", False)]
        out.append(
            CommandDoc(name, _usage(name, params), command.help or "", [_option(p) for p in params])
        )
    return out


def main_help() -> str:
    """The help of ``tether`` itself."""
    return typer.main.get_command(app).help or ""
