"""Compiled kernels: one switch for every fast path, numba imported only when it pays.

The hot paths of the strategies (line-of-sight clearance, the weights and gradient of
App. A, closest points on paths) have a compiled kernel next to their reference code.
Both give the same results (tests compare them: exactly for combinatorial results, to
the last bit where the arithmetic is the same), so which one runs changes nothing but
the time. :func:`enabled` decides, from ``TETHER_JIT``:

* ``0`` (or ``off``): the reference (numpy) paths everywhere;
* ``1`` (or ``on``): the kernels whenever numba is importable (compiled on first use);
* ``auto`` (the default): the reference paths first; once the process has spent
  ``TETHER_JIT_AFTER_S`` seconds (default 2) since its first hot-path call, the kernels
  -- if numba's cache already holds them. Starting numba costs about a second and
  compiling the kernels a minute or more, so a short run never pays either; a long run
  switches after two seconds. When the cache is cold, a background process
  (``python -m tether.continuous.kernels``, low priority) compiles it, and this process
  keeps the reference paths until the background process is done.

Paths every strategy shares (line of sight of the sensing graph, team metrics) use
their kernel only when numba is already loaded (:func:`warm`), so ``silent`` and
``recurrent`` never import it. :func:`set_enabled` / :func:`using` force the choice
(tests and benchmarks compare both).
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import subprocess
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

#: modules whose compiled code the ``auto`` switch waits for (their ``warm_up`` compiles all)
KERNEL_MODULES = (
    "continuous/kernels.py",
    "continuous/tracking_kernels.py",
    "continuous/force_kernels.py",
    "continuous/dynamics_kernels.py",
    "continuous/pair_kernels.py",
    "graph/lapack_kernels.py",
    "continuous/round_kernels.py",
    "continuous/bookkeep_kernels.py",
    "comm_kernels.py",
    "world/clearance_kernels.py",
    "world/clearance_cache_kernels.py",
    "world/los_kernels.py",
    "paths/astar_kernels.py",
    "graph/kernels.py",
    "graph/grid_kernels.py",
    "graph/metrics_kernels.py",
    "graph/link_kernels.py",
    "paths/geodesic_kernels.py",
    "graph/small_kernels.py",
    "recurrent/planning/steiner_kernels.py",
    "recurrent/planning/expgraph_kernels.py",
    "recurrent/planning/apx_kernels.py",
    "recurrent/planning/ilp_kernels.py",
    "silent/steering_kernels.py",
    "sensing/robots_kernels.py",
    "sensing/depth_kernels.py",
    "sensing/draws_kernels.py",
)

_forced: bool | None = None
_mode: str | None = None
_switched = False
_first_hot: float | None = None
_next_check = 0.0
_spawned = False


def available() -> bool:
    """numba can be imported."""
    return importlib.util.find_spec("numba") is not None


def mode() -> str:
    """``on``, ``off`` or ``auto`` (from ``TETHER_JIT``, read once per process)."""
    global _mode
    if _mode is None:
        raw = os.environ.get("TETHER_JIT", "auto").strip().lower()
        _mode = {"0": "off", "off": "off", "1": "on", "on": "on"}.get(raw, "auto")
        if not available():
            _mode = "off"
    return _mode


def enabled() -> bool:
    """The compiled kernels run now (see the module docstring)."""
    global _switched, _first_hot
    if _forced is not None:
        return _forced
    m = mode()
    if m != "auto":
        return m == "on"
    if _switched:
        return True
    now = time.perf_counter()
    if _first_hot is None:
        _first_hot = now
    if now - _first_hot < _after_s() or now < _next_check:
        return False
    _switched = _cache_ready(now)
    return _switched


def warm() -> bool:
    """The kernels run and numba is already loaded in this process.

    Paths shared by every strategy (line of sight of the sensing graph, the team's
    metrics) use their kernel only then: a strategy without kernels (``silent``,
    ``recurrent``) then never pays numba's start-up for them.
    """
    return enabled() and "numba" in sys.modules


def set_enabled(value: bool | None) -> None:
    """Force the kernels on (``True``) or off (``False``); ``None`` restores ``TETHER_JIT``."""
    global _forced
    if value and not available():
        raise RuntimeError("the compiled kernels need numba: pip install numba")
    _forced = value


@contextmanager
def using(value: bool) -> Iterator[None]:
    """Run a block with the kernels on or off (tests and benchmarks compare both)."""
    before = _forced
    set_enabled(value)
    try:
        yield
    finally:
        set_enabled(before)


def _after_s() -> float:
    try:
        return float(os.environ.get("TETHER_JIT_AFTER_S", "2.0"))
    except ValueError:
        return 2.0


# -- the compiled-code marker ----------------------------------------------------------


def marker() -> Path:
    """The file that says numba's cache holds this code's kernels (written by warm-up).

    Its name hashes the kernel sources and the numba, numpy and Python versions, so a
    change to any of them means a cold cache again.
    """
    root = Path(__file__).resolve().parent
    h = hashlib.sha256()
    for rel in KERNEL_MODULES:
        path = root / rel
        h.update(path.read_bytes() if path.exists() else rel.encode())
    try:
        from importlib.metadata import version

        h.update(f"{version('numba')} {version('numpy')} {sys.version}".encode())
    except Exception:  # noqa: BLE001 - versions only refine the key
        h.update(sys.version.encode())
    h.update(os.environ.get("NUMBA_CACHE_DIR", "").encode())
    name = f"tether-kernels-{h.hexdigest()[:16]}.ready"
    base = os.environ.get("NUMBA_CACHE_DIR")
    if base:
        return Path(base) / name
    local = root / "__pycache__"
    if os.access(local if local.exists() else root, os.W_OK):
        return local / name
    return Path.home() / ".cache" / "tether" / name


def _cache_ready(now: float) -> bool:
    """True if the marker exists; else start the background warm-up (once) and say no."""
    global _next_check, _spawned
    _next_check = now + 5.0  # a stat every five seconds at most
    path = marker()
    if path.exists():
        return True
    if not _spawned:
        _spawned = True
        lock = path.with_suffix(".lock")
        try:
            if lock.exists() and time.time() - lock.stat().st_mtime < 1800:
                return False  # another process is compiling
            lock.parent.mkdir(parents=True, exist_ok=True)
            lock.write_text(str(os.getpid()))
            env = dict(os.environ)
            src = str(Path(__file__).resolve().parents[1])
            env["PYTHONPATH"] = os.pathsep.join([src, env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
            cmd = [sys.executable, "-m", "tether.continuous.kernels"]  # its warm_up()
            subprocess.Popen(cmd, env=env, start_new_session=True,
                             stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                             stderr=subprocess.DEVNULL)  # fmt: skip
        except OSError:
            pass
    return False


def write_marker(seconds: float) -> None:
    """Record that every kernel is in numba's cache (after a complete warm-up)."""
    path = marker()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(f"warm-up {seconds:.1f} s\n")
        path.with_suffix(".lock").unlink(missing_ok=True)
    except OSError:
        pass
