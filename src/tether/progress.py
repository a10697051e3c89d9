"""Progress of a long command in one look: a bar with the time left on a terminal.

:func:`progress_bar` is the bar every command draws (``tether run``'s steps, ``tether
sweep``'s trials, ``tether animate``'s frames, ``tether export``'s steps): what is
counted, the bar, done / total, elapsed and time left. Where the output is not a
terminal (a log file, CI), the bar draws nothing; :class:`StepProgress` then prints a
plain line every tenth of the way instead. Work that has no count (building a world,
placing a large team, checking a sweep's combinations) shows what it is doing and for
how long once it has lasted :data:`AFTER_S` (:class:`Working`).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from typing import Any

__all__ = ["StepProgress", "Working", "progress_bar"]

#: plain progress lines per run when the output is not a terminal
PLAIN_LINES = 10
#: seconds of work without a count before :class:`Working` shows it
AFTER_S = 2.0
#: seconds between :class:`Working`'s plain lines when the output is not a terminal
EVERY_S = 30.0


def progress_bar(label: str, console: Any = None, *, transient: bool = True,
                 extra: tuple[Any, ...] = ()) -> Any:  # fmt: skip
    """A :class:`rich.progress.Progress`: ``label``, bar, done / total, elapsed, time left.

    ``extra`` columns go after done / total. Disabled (draws nothing) when ``console``
    (default: standard output) is not a terminal.
    """
    from rich.console import Console
    from rich.progress import (
        BarColumn,
        MofNCompleteColumn,
        Progress,
        TextColumn,
        TimeElapsedColumn,
        TimeRemainingColumn,
    )

    console = console if console is not None else Console()
    return Progress(
        TextColumn(label),
        BarColumn(),
        MofNCompleteColumn(),
        *extra,
        TextColumn("elapsed"),
        TimeElapsedColumn(),
        TextColumn("left"),
        TimeRemainingColumn(),
        console=console,
        transient=transient,
        disable=not console.is_terminal,
    )


class StepProgress:
    """The steps of one run: a bar on a terminal, else a line every tenth of the way.

    Call it with each step as the run records it (``tether.runner.run``'s
    ``progress``); :meth:`stop` ends the bar (also when the run is interrupted).

    Parameters
    ----------
    console : rich.console.Console
        Where the bar goes (a terminal or not).
    say : callable
        Where plain lines go when ``console`` is not a terminal.
    total : int
        The run's ``sim.max_steps`` (a strategy may finish earlier).
    preparing : str, optional
        What happens before the first step (shown by :class:`Working` until then).
    """

    def __init__(
        self, console: Any, say: Callable[[str], None], total: int, preparing: str | None = None
    ) -> None:
        self.total = max(int(total), 1)
        self.say = say
        self._console = console
        self._bar = None
        self._task: Any = None
        self._before = None if preparing is None else Working(preparing, console, say).start()
        self._chunk = max(self.total // 1000, 1)  # bar updates, at most a thousand per run
        self._next_line = self.total / PLAIN_LINES
        self._shown = 0

    def __call__(self, step: int) -> None:
        if self._before is not None:  # the first step: the run is prepared
            self._before.stop()
            self._before = None
        if self._bar is None and getattr(self._console, "is_terminal", False):
            self._bar = progress_bar("steps", self._console)
            self._bar.start()
            self._task = self._bar.add_task("run", total=self.total)
        if self._bar is not None:
            if step - self._shown >= self._chunk:
                self._bar.update(self._task, completed=step)
                self._shown = step
        elif step >= self._next_line and step < self.total:
            self.say(f"step {step:,} of {self.total:,} ({100 * step // self.total} %)")
            while self._next_line <= step:
                self._next_line += self.total / PLAIN_LINES

    def stop(self) -> None:
        if self._before is not None:
            self._before.stop()
            self._before = None
        if self._bar is not None:
            self._bar.stop()
            self._bar = None
        self._console = None  # a step reported after the stop draws nothing


class Working:
    """Work without a count, shown once it has lasted ``after_s``: what it is and how long
    it has taken, as a spinner on a terminal, else a plain line every ``every_s`` seconds.
    Nothing is shown for work that ends sooner.

    A thread of the command watches the time; :meth:`stop` (or leaving the ``with``
    block, also on an error or Ctrl-C) ends it and clears the spinner.

    Parameters
    ----------
    label : str
        What is being done, e.g. ``"building the world and placing 300 robots"``.
    console : rich.console.Console
        Where the spinner goes (a terminal or not).
    say : callable
        Where plain lines go when ``console`` is not a terminal.
    after_s, every_s : float, optional
        Default :data:`AFTER_S` and :data:`EVERY_S`.
    """

    def __init__(
        self,
        label: str,
        console: Any,
        say: Callable[[str], None],
        *,
        after_s: float | None = None,
        every_s: float | None = None,
    ) -> None:
        self.label = label
        self.say = say
        self.after_s = AFTER_S if after_s is None else after_s
        self.every_s = EVERY_S if every_s is None else every_s
        self._console = console if getattr(console, "is_terminal", False) else None
        self._done = threading.Event()
        self._thread: threading.Thread | None = None
        self._spinner: Any = None

    def start(self) -> Working:
        self._thread = threading.Thread(target=self._watch, name="tether-working", daemon=True)
        self._thread.start()
        return self

    def stop(self) -> None:
        self._done.set()
        if self._thread is not None:
            self._thread.join()
            self._thread = None
        if self._spinner is not None:
            self._spinner.stop()
            self._spinner = None

    def __enter__(self) -> Working:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def _watch(self) -> None:
        began = time.monotonic()
        if self._done.wait(self.after_s):
            return
        if self._console is None:  # plain lines until the work ends
            wait = 0.0
            while not self._done.wait(wait):
                self.say(f"{self.label} ... ({time.monotonic() - began:.0f} s)")
                wait = self.every_s
            return
        from rich.progress import Progress, SpinnerColumn, TextColumn

        spinner = Progress(SpinnerColumn(), TextColumn("{task.description}"),
                           console=self._console, transient=True)  # fmt: skip
        task = spinner.add_task(self.label)
        spinner.start()
        self._spinner = spinner  # stopped by stop(), in the command's own thread
        while not self._done.wait(1.0):
            spinner.update(task, description=f"{self.label} ({time.monotonic() - began:.0f} s)")
