"""Rows, lines and clocks of the benchmark suite.

A *row* is a function registered with :func:`row`; it measures one thing a user pays
for and returns :class:`Line` s (one per size or case: what the tables show) and
optional details (per-instance data for the detail tables). A line carries its goal,
its peer (what it is compared with in the same run, if anything) and the warm-up
(first calls: imports, numba's compilation or cache load) apart from the steady state.
"""

from __future__ import annotations

import json
import os
import resource
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[2]


@dataclass
class Line:
    """One measured line of a row (a size, a case) in its display unit."""

    label: str
    """What was measured, e.g. ``"connectivity step, 35 robots, free 3-D"``."""
    unit: str
    """Display unit of ``ours`` and ``peer_value``: ``us``, ``ms``, ``s``, ``x``, ``/s``..."""
    ours: float
    """The steady-state value (medians unless the label says otherwise)."""
    goal: str = "-"
    """The goal as text, e.g. ``"<= 50 us"``; ``"-"`` for none."""
    goal_value: float | None = None
    """The goal's threshold on ``ours`` (or on the ratio, :attr:`goal_on`)."""
    goal_on: str = "ours"
    """``"ours"`` or ``"ratio"``: what :attr:`goal_value` bounds."""
    higher_is_better: bool = False
    peer: str = "-"
    """The peer timed in the same run, e.g. ``"networkx mehlhorn"``; ``"-"`` for none."""
    peer_value: float | None = None
    warmup_s: float | None = None
    """Seconds of the first call(s) (compile or cache load included), apart."""
    extra: dict[str, Any] = field(default_factory=dict)

    @property
    def ratio(self) -> float | None:
        """``ours / peer_value`` (lower is better for times, higher for rates)."""
        if self.peer_value in (None, 0):
            return None
        return self.ours / self.peer_value

    @property
    def met(self) -> bool | None:
        """Whether the goal holds (``None``: no goal)."""
        if self.goal_value is None:
            return None
        value = self.ratio if self.goal_on == "ratio" else self.ours
        if value is None:
            return None
        return value >= self.goal_value if self.higher_is_better else value <= self.goal_value

    def as_dict(self) -> dict[str, Any]:
        out = asdict(self)
        out["ratio"], out["met"] = self.ratio, self.met
        return out


@dataclass
class Row:
    """A registered row: its name, what it measures, and its function."""

    name: str
    title: str
    run: Callable[[bool], dict[str, Any]]
    """``run(quick) -> {"lines": [Line, ...], "details": {...}}``."""
    full_only: bool = False
    """Skipped by ``--quick`` (minutes even when small)."""


ROWS: dict[str, Row] = {}


def row(name: str, title: str, *, full_only: bool = False) -> Callable:
    """Register ``fn(quick) -> {"lines": [...], "details": {...}}`` as the row ``name``."""

    def register(fn: Callable[[bool], dict[str, Any]]) -> Callable[[bool], dict[str, Any]]:
        if name in ROWS:
            raise ValueError(f"row {name!r} registered twice")
        ROWS[name] = Row(name, title, fn, full_only)
        return fn

    return register


def cpu_clock() -> float:
    """The clock of every in-process timing: this process's CPU time.

    The development machines are 2 cores shared with other jobs, where wall times are
    several times the CPU times; the kernels are serial and BLAS runs one thread.
    """
    return time.process_time()


def batch(fn: Callable[[], object], calls: int) -> float:
    """Seconds per call of ``calls`` calls of ``fn``, the clock read once around them
    (reading a CPU clock costs microseconds on a VM, which a per-call reading adds)."""
    t0 = cpu_clock()
    for _ in range(calls):
        fn()
    return (cpu_clock() - t0) / calls


def warm_then_steady(
    fn: Callable[[], object], calls: int, rounds: int = 3, warmup_calls: int = 1
) -> tuple[float, float]:
    """``(warm-up seconds, steady seconds per call)``: the first ``warmup_calls`` calls
    timed together, then the median over ``rounds`` batches of ``calls`` calls."""
    t0 = cpu_clock()
    for _ in range(warmup_calls):
        fn()
    warm = cpu_clock() - t0
    return warm, statistics.median(batch(fn, calls) for _ in range(rounds))


def paired(fns: dict[str, Callable[[], object]], rounds: int) -> dict[str, float]:
    """Median seconds per call of each function, the functions called in turns
    (a, b, a, b, ...) so that the machine's other load falls on all alike."""
    times: dict[str, list[float]] = {k: [] for k in fns}
    for _ in range(rounds):
        for key, fn in fns.items():
            t0 = cpu_clock()
            fn()
            times[key].append(cpu_clock() - t0)
    return {k: statistics.median(v) for k, v in times.items()}


def fresh_process(
    code: str, env: dict[str, str] | None = None, timeout_s: float = 900.0
) -> tuple[dict[str, Any], float, float]:
    """Run ``python -c code`` in a fresh process; ``(its last stdout line as JSON, wall
    seconds, CPU seconds of the child)``. ``env`` entries set to ``""`` are removed."""
    full = dict(os.environ)
    for key, value in (env or {}).items():
        if value == "":
            full.pop(key, None)
        else:
            full[key] = value
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(
        [sys.executable, "-c", code],
        env=full,
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=timeout_s,
        check=False,
    )
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise RuntimeError(f"child process failed ({proc.returncode}): {proc.stderr[-2000:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    lines = proc.stdout.strip().splitlines()
    return (json.loads(lines[-1]) if lines else {}), wall, cpu


def command(
    argv: list[str], env: dict[str, str] | None = None, timeout_s: float = 900.0
) -> tuple[float, float]:
    """``(wall seconds, CPU seconds)`` of a command in a fresh process (must exit 0)."""
    full = dict(os.environ, **(env or {}))
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    proc = subprocess.run(
        argv, env=full, cwd=ROOT, capture_output=True, text=True, timeout=timeout_s, check=False
    )
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        raise RuntimeError(f"{' '.join(argv[:4])} failed: {proc.stderr[-2000:]}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def tether_cli() -> list[str]:
    """The ``tether`` command of this interpreter (as a fresh process)."""
    return [sys.executable, "-c", "import sys; from tether.cli import main; sys.exit(main())"]
