from __future__ import annotations

from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SHARED_MAPS = ROOT.parent / "shared" / "maps"


@pytest.fixture
def shared_maps() -> Path:
    if not SHARED_MAPS.is_dir():
        pytest.skip(f"shared maps folder {SHARED_MAPS} is absent (it sits beside the repo in CI)")
    return SHARED_MAPS


@pytest.fixture
def skip_without_shared_map():
    """Call with a scenario: skips the test if it names a ../shared/maps file that is absent.

    Built-in scenarios on the shared maps run from a checkout (the maps are test data,
    not shipped); elsewhere the test skips cleanly with the reason.
    """

    def check(scenario) -> None:
        path = scenario.world.params.get("path")
        if path and "shared/maps" in str(path) and not scenario.resolve_path(path).exists():
            pytest.skip(f"{path} not found (the shared maps are test data outside the package)")

    return check
