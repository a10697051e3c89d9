"""Scenario YAML reads exponent floats as YAML 1.2 does (``1e-6``, ``2.5e3``), in files and
in ``--set``: PyYAML alone (YAML 1.1) made them strings, which scene and map parameters
then refused as "not a number"."""

from __future__ import annotations

import pytest

from _cli import tether
from tether.config import parse_yaml


@pytest.mark.parametrize(
    ("text", "value"),
    [("1e-6", 1e-6), ("2.5e3", 2500.0), ("-1E+7", -1e7), (".5e2", 50.0), ("1.0e-6", 1e-6)],
)
def test_exponent_floats_are_floats(text: str, value: float) -> None:
    got = parse_yaml(text, "x")
    assert isinstance(got, float) and got == value


@pytest.mark.parametrize("text", ["1e", "e5", "abc1e5", "1e5x", "v1.2e3"])
def test_other_strings_stay_strings(text: str) -> None:
    assert parse_yaml(text, "x") == text


def test_set_with_an_exponent_reaches_the_scene_as_a_number(capsys) -> None:
    code, out, _ = tether(
        capsys, "validate", "connectivity_empty", "--set", "world.params.resolution_m=2.5e-1"
    )
    assert code == 0, out
    code, _, err = tether(
        capsys, "validate", "connectivity_empty", "--set", "world.params.resolution_m=1e-6"
    )
    assert code == 2 and "cells, more than" in err  # judged as a number, not "must be a number"
