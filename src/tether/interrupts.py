"""Stopping as Unix tools stop: Ctrl-C (SIGINT) and SIGTERM become an exception.

Python dies at once on SIGTERM (no ``finally``, no cleanup) and turns SIGINT into a
``KeyboardInterrupt`` that libraries may catch. While :func:`stop_on_signals` is active,
both raise :class:`Stopped` instead: it unwinds the stack like any exception, so a run
folder being written is removed (:class:`tether.runfolder.RunFolder` aborts on any
exception), worker processes are stopped, and the command exits with ``128 + signal``
(130 for SIGINT, 143 for SIGTERM). :class:`Stopped` derives from ``SystemExit``: code
that catches ``Exception`` lets it through, and a process that does not catch it exits
with that code.

A signal that arrives while Python runs a weak-reference callback or a ``__del__``
raises there, where Python prints "Exception ignored" and carries on. So the handler
also records the signal, and long loops call :func:`raise_if_stopped` once per
iteration: a stop that was swallowed is raised again at the next step.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType

__all__ = ["Stopped", "raise_if_stopped", "stop_on_signals"]

#: the signals a command stops on
SIGNALS = (signal.SIGINT, signal.SIGTERM)

#: the signal that asked this process to stop, while a handler of this module is set
_received: int | None = None


class Stopped(SystemExit):
    """The process was asked to stop by signal ``signum``; ``code`` is ``128 + signum``.

    ``note`` says what the stop left behind (set by the command that knows).
    """

    def __init__(self, signum: int) -> None:
        super().__init__(128 + int(signum))
        self.signum = int(signum)
        self.note = ""

    @property
    def signal_name(self) -> str:
        return signal.Signals(self.signum).name

    def __str__(self) -> str:
        how = " (Ctrl-C)" if self.signum == signal.SIGINT else ""
        return f"interrupted by {self.signal_name}{how}" + (f": {self.note}" if self.note else "")


def raise_if_stopped() -> None:
    """Raise :class:`Stopped` if a stop signal was received (call once per loop iteration).

    Without a signal this is one global read. With one, the first :class:`Stopped` has
    normally unwound the loop already; this raises it again only where it was swallowed.
    """
    if _received is not None:
        raise Stopped(_received)


def _record(signum: int | None) -> None:
    global _received
    _received = signum


@contextmanager
def stop_on_signals(*, once: bool = True) -> Iterator[None]:
    """Raise :class:`Stopped` on SIGINT and SIGTERM inside the block (main thread only).

    With ``once`` (the default), only the first signal raises; later ones are ignored
    so that the cleanup the first one started is not itself interrupted. The previous
    handlers are restored on exit. Outside the main thread, where Python cannot set
    handlers, the block runs unchanged.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    fired = False

    def handler(signum: int, frame: FrameType | None) -> None:
        nonlocal fired
        if fired and once:
            return
        fired = True
        _record(signum)
        raise Stopped(signum)

    previous = {s: signal.signal(s, handler) for s in SIGNALS}
    try:
        yield
    finally:
        for s, old in previous.items():
            signal.signal(s, old)
        _record(None)  # the stop is handled; a later block starts afresh


def raise_on_sigterm() -> None:
    """In a worker process: SIGTERM raises :class:`Stopped`, SIGINT is ignored (the parent
    process receives Ctrl-C and stops its workers with SIGTERM, in order)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)

    def handler(signum: int, frame: FrameType | None) -> None:
        signal.signal(signal.SIGTERM, signal.SIG_IGN)  # one stop is enough
        _record(signum)
        raise Stopped(signum)

    signal.signal(signal.SIGTERM, handler)
