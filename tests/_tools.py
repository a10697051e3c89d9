"""Tests that need a tool outside Python (Chromium, ffmpeg): skip here, fail under CI."""

from __future__ import annotations

import os

import pytest

#: set by .ci/run: a test that needs Chromium or ffmpeg fails without it instead of skipping
REQUIRE_TOOLS = os.environ.get("TETHER_REQUIRE_TOOLS", "") == "1"


def skip_unless_required(reason: str) -> None:
    """Skip for ``reason`` on a developer's machine; fail under CI (``TETHER_REQUIRE_TOOLS=1``)."""
    if REQUIRE_TOOLS:
        pytest.fail(f"{reason}; TETHER_REQUIRE_TOOLS=1 (CI) needs it installed")
    pytest.skip(reason)
