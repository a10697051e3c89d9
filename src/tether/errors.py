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


class OutputError(TetherError):
    """An output folder cannot be written, or would mix two runs' files."""
