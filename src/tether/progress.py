"""Progress of a long command in one look: a bar with the time left on a terminal.

:func:`progress_bar` is the bar every command draws (``tether run``'s steps, ``tether
sweep``'s trials, ``tether animate``'s frames, ``tether export``'s steps): what is
counted, the bar, done / total, elapsed and time left. Where the output is not a
terminal (a log file, CI), the bar draws nothing; :class:`StepProgress` then prints a
plain line every tenth of the way instead.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

__all__ = ["StepProgress", "progress_bar"]

#: plain progress lines per run when the output is not a terminal
PLAIN_LINES = 10


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
    """

    def __init__(self, console: Any, say: Callable[[str], None], total: int) -> None:
        self.total = max(int(total), 1)
        self.say = say
        self._bar = None
        self._task: Any = None
        if getattr(console, "is_terminal", False):
            self._bar = progress_bar("steps", console)
            self._bar.start()
            self._task = self._bar.add_task("run", total=self.total)
        self._chunk = max(self.total // 1000, 1)  # bar updates, at most a thousand per run
        self._next_line = self.total / PLAIN_LINES
        self._shown = 0

    def __call__(self, step: int) -> None:
        if self._bar is not None:
            if step - self._shown >= self._chunk:
                self._bar.update(self._task, completed=step)
                self._shown = step
        elif step >= self._next_line and step < self.total:
            self.say(f"step {step:,} of {self.total:,} ({100 * step // self.total} %)")
            while self._next_line <= step:
                self._next_line += self.total / PLAIN_LINES

    def stop(self) -> None:
        if self._bar is not None:
            self._bar.stop()
            self._bar = None
