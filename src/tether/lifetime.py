"""No process of tether outlives the command that started it.

Child processes (a sweep's workers, the kernel compiler) call :func:`die_with_parent`
when they start: on Linux the kernel kills them the moment their parent dies, however it
dies (``kill -9`` included); everywhere a watchdog thread also ends them within half a
second of finding that their parent is gone.
"""

from __future__ import annotations

import contextlib
import ctypes
import os
import signal
import sys
import threading
import time
from functools import lru_cache
from typing import Any

__all__ = ["die_with_parent", "kill_on_parent_death", "prctl_function"]

_PR_SET_PDEATHSIG = 1
#: how often the watchdog looks for its parent (seconds)
WATCH_S = 0.5


@lru_cache(maxsize=1)
def prctl_function() -> Any:
    """libc's ``prctl`` (Linux), looked up once: a child between fork and exec only calls it."""
    if not sys.platform.startswith("linux"):
        return None
    try:
        return ctypes.CDLL(None, use_errno=True).prctl
    except (OSError, AttributeError):
        return None


def kill_on_parent_death() -> bool:
    """Ask Linux to send SIGKILL to this process when its parent dies (``prctl``).

    Usable between ``fork`` and ``exec`` (a ``preexec_fn``; call :func:`prctl_function`
    in the parent first, so that the child only makes the call): the request survives
    ``exec``.
    Returns False where the call is not available.
    """
    prctl = prctl_function()
    return prctl is not None and prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) == 0


def die_with_parent(parent_pid: int | None = None) -> None:
    """End this process when its parent ends (see the module docstring).

    Parameters
    ----------
    parent_pid
        The parent's process id as the parent saw it (``os.getpid()`` there). If the
        parent is already gone when this runs, the process ends at once.
    """
    parent = os.getppid() if parent_pid is None else parent_pid
    kill_on_parent_death()
    if os.getppid() != parent:  # the parent died before we could ask
        os._exit(1)

    def watch() -> None:
        while os.getppid() == parent:
            time.sleep(WATCH_S)
        with contextlib.suppress(Exception):
            sys.stderr.flush()
        os._exit(1)

    threading.Thread(target=watch, name="tether-parent-watch", daemon=True).start()
