"""Compiled kernels: one switch for every fast path, numba imported only when it pays.

The hot paths of the strategies (line-of-sight clearance, the weights and gradient of
App. A, closest points on paths) have a compiled kernel next to their reference code.
Both give the same results (tests compare them: exactly for combinatorial results, to
the last bit where the arithmetic is the same), so which one runs changes nothing but
the time. :func:`enabled` decides, from ``TETHER_JIT``:

* ``0`` (or ``off``): the reference (numpy) paths everywhere;
* ``1`` (or ``on``): the kernels whenever numba is importable (compiled on first use);
* ``auto`` (the default): the reference paths first; once the process has spent
  ``TETHER_JIT_AFTER_S`` seconds (default 2) since its first hot-path call, the kernels.
  Starting numba costs about a second, so a short run never pays it; a long run
  switches after two seconds. When numba's cache does not hold the kernels yet, this
  process compiles them then, once, with a line on stderr saying so (a child process,
  ``python -m tether.kernel_cache``, that the command waits for and that dies with
  it: nothing keeps running after tether exits), and later runs load them from the
  cache. ``python -m tether.kernel_cache`` compiles them ahead of time. While
  another process compiles, this one keeps the reference paths.

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
    "continuous/connectivity/kernels.py",
    "continuous/exploration/tracking_kernels.py",
    "continuous/exploration/substep_kernels.py",
    "continuous/exploration/step_kernels.py",
    "continuous/exploration/reference_filter_kernels.py",
    "continuous/exploration/recruit_kernels.py",
    "continuous/connectivity/force_kernels.py",
    "continuous/connectivity/dynamics_kernels.py",
    "continuous/connectivity/pair_kernels.py",
    "continuous/connectivity/potential_kernels.py",
    "graph/lapack_kernels.py",
    "continuous/exploration/round_kernels.py",
    "continuous/connectivity/bookkeep_kernels.py",
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

#: the child process that compiles every kernel into numba's cache (the marker's path is
#: appended; tether.kernel_cache's warm-up writes the marker itself and ignores it)
COMPILE_COMMAND = [sys.executable, "-m", "tether.kernel_cache"]

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


def allowed() -> bool:
    """The kernels may run: not switched off (``TETHER_JIT=0``, :func:`set_enabled`).

    For code that runs compiled anyway (the vector environment steps in numba), where
    the ``auto`` mode's wait would save no start-up: its own kernels run at once unless
    switched off, and its reference paths run when they are.
    """
    if _forced is not None:
        return _forced
    return mode() != "off"


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
    """True if the kernels are in numba's cache; else compile them now (once per process)."""
    global _next_check, _spawned
    _next_check = now + 5.0  # a stat every five seconds at most
    path = marker()
    if path.exists():
        return True
    if _spawned:
        return False
    _spawned = True
    return compile_kernels(path)


def _take_lock(lock: Path) -> bool:
    """Create ``lock`` holding this process id; False while another live process holds it."""
    for _ in range(2):
        try:
            fd = os.open(lock, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            try:
                holder = int(lock.read_text().strip() or "0")
                fresh = time.time() - lock.stat().st_mtime < 1800
            except (OSError, ValueError):
                holder, fresh = 0, False
            if holder > 0 and fresh and _alive(holder):
                return False
            lock.unlink(missing_ok=True)  # left by a process that died
            continue
        with os.fdopen(fd, "w") as fh:
            fh.write(str(os.getpid()))
        return True
    return False


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # another user's process
        return True
    return True


def compile_kernels(path: Path | None = None) -> bool:
    """Compile every kernel into numba's cache in a child process, waiting for it.

    The child (``python -m tether.kernel_cache``) is killed if this process stops
    waiting (an exception, Ctrl-C) and by the kernel if this process dies
    (:func:`tether.lifetime.kill_on_parent_death`). A line on stderr says what happens.
    Returns True when the kernels are compiled.
    """
    from tether.lifetime import kill_on_parent_death, prctl_function

    prctl_function()  # looked up here, so that the child only calls it
    path = marker() if path is None else path
    lock = path.with_suffix(".lock")
    try:
        lock.parent.mkdir(parents=True, exist_ok=True)
        if not _take_lock(lock):
            return False  # another process compiles: the reference paths until it is done
    except OSError:
        return False
    start = time.perf_counter()
    _say("tether: compiling the numba kernels once (about a minute; later runs reuse them) ...")
    proc = None
    try:
        env = dict(os.environ)
        src = str(Path(__file__).resolve().parents[1])
        env["PYTHONPATH"] = os.pathsep.join([src, env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
        proc = subprocess.Popen(COMPILE_COMMAND + [str(path)], env=env, stdin=subprocess.DEVNULL,
                                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                preexec_fn=kill_on_parent_death)  # fmt: skip
        proc.wait()
    except OSError:
        pass
    finally:
        if proc is not None and proc.poll() is None:
            proc.kill()
            proc.wait()
        lock.unlink(missing_ok=True)
    ok = path.exists()
    seconds = time.perf_counter() - start
    if ok:
        _say(f"tether: kernels compiled in {seconds:.0f} s")
    else:
        _say(f"tether: compiling the kernels failed after {seconds:.0f} s; numpy paths run")
    return ok


def _say(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


def write_marker(seconds: float) -> None:
    """Record that every kernel is in numba's cache (after a complete warm-up)."""
    path = marker()
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(f"warm-up {seconds:.1f} s\n")
        path.with_suffix(".lock").unlink(missing_ok=True)
    except OSError:
        pass
