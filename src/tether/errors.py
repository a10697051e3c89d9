"""Errors that reach the user as one clear line (never a traceback)."""

from __future__ import annotations


class TetherError(Exception):
    """Base class for errors the CLI prints as a single line.

    The message should name the file, the field and what is expected, e.g.
    ``scenario.yaml: sensing.range_m: must be > 0 (got -3)``.
    """


class ScenarioError(TetherError):
    """A scenario file is missing, malformed or describes an impossible setup."""


class MapError(TetherError):
    """A map file is missing, corrupt or inconsistent with its metadata."""

    @classmethod
    def at(cls, path: object, field_name: str | None, message: str) -> MapError:
        """A one-line error ``"<file>: <field>: <message>"`` (whitespace collapsed)."""
        message = " ".join(str(message).split())
        where = f"{path}: {field_name}: " if field_name else f"{path}: "
        return cls(where + message)


class OutputError(TetherError):
    """An output folder cannot be written, or would mix two runs' files."""


class TetherWarning(UserWarning):
    """Something the user should know about a run that still runs (one line).

    The command line prints it as ``warning: <message>``; e.g. a map file not found and
    replaced by its stand-in (``world.params.stand_in_path``).
    """
