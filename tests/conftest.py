from __future__ import annotations

import os
from pathlib import Path

# Which path a test runs is never left to chance: ``TETHER_JIT=auto`` (the library's
# default) switches to the compiled kernels after two seconds if numba's cache is warm,
# so a test would run one path or the other by the machine's history. Unless the caller
# pins it (``TETHER_JIT=1 pytest`` runs every test compiled), tests and the commands
# they start run the numpy reference; tests of the kernels pin their path with
# ``tether.jit.using`` and compare it with the reference (test_jit_paths.py, test_kernels.py).
if os.environ.get("TETHER_JIT", "").strip().lower() not in ("0", "off", "1", "on"):
    os.environ["TETHER_JIT"] = "0"

import pytest  # noqa: E402

from tether import jit  # noqa: E402

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


@pytest.fixture(autouse=True)
def _path_restored():
    """A test that pins the path with ``jit.set_enabled`` does not pin it for the next."""
    yield
    jit.set_enabled(None)
