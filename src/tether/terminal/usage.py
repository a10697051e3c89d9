"""Usage errors of the command line (typer / click) as one ``error:`` line."""

from __future__ import annotations

import typer

__all__ = ["usage_error_class", "usage_line"]


def usage_error_class() -> type[Exception]:
    """The click exception class behind typer's usage errors, found without importing click.

    typer bundles its own copy of click (``typer._click``) in recent versions and
    depends on ``click`` in older ones; ``typer.BadParameter`` is public in both,
    and its bases include the ``ClickException`` every usage error derives from.
    """
    for cls in typer.BadParameter.__mro__:
        if cls.__name__ == "ClickException":
            return cls
    return typer.BadParameter  # pragma: no cover (every typer so far has one)


def usage_line(exc: Exception) -> str:
    """``error: <what> (see `tether <command> --help`)`` for a usage error."""
    message = " ".join(str(exc.format_message()).split())  # type: ignore[attr-defined]
    ctx = getattr(exc, "ctx", None)
    command = getattr(ctx, "command_path", None) or "tether"
    if not command.startswith("tether"):
        command = "tether " + command.split(" ", 1)[-1] if " " in command else "tether"
    return f"error: {message} (see `{command} --help`)"
