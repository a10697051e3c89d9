"""Progress of a sweep: a rich progress bar on a terminal, one plain line per trial elsewhere.

Both show what :func:`tether.experiments.sweep.run_trials` reports: trials done (run
now or found finished), trials failed and, on the bar, the time left.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Protocol

from tether.experiments.executors import TrialOutcome
from tether.progress import Working, progress_bar

__all__ = ["LineProgress", "Preparing", "RichProgress", "TrialProgress", "progress_for"]


class TrialProgress(Protocol):
    """What a sweep tells about its progress."""

    def start(self, total: int, skipped: int) -> None:
        """``total`` trials to run now; ``skipped`` found finished in the folder."""

    def advance(self, outcome: TrialOutcome, done: int, failed: int) -> None:
        """One more trial finished (``outcome``); ``done`` and ``failed`` so far (this run)."""

    def stop(self) -> None:
        """The sweep's trials are all finished (or it was interrupted)."""


class LineProgress:
    """One plain line per trial, ``[k/n] <run folder> done`` or ``... failed: <error>``.

    Parameters
    ----------
    say : callable
        Where a line goes (e.g. ``print``).
    """

    def __init__(self, say: Callable[[str], None]) -> None:
        self.say = say
        self.total = 0

    def start(self, total: int, skipped: int) -> None:
        self.total = total

    def advance(self, outcome: TrialOutcome, done: int, failed: int) -> None:
        status = "done" if outcome.summary is not None else f"failed: {outcome.error}"
        self.say(f"[{done + failed}/{self.total}] {outcome.trial.run_dir} {status}")

    def stop(self) -> None:
        pass


class RichProgress:
    """A rich progress bar: trials done / total, failed, elapsed and time left.

    Parameters
    ----------
    console : rich.console.Console
        The terminal to draw on.
    """

    def __init__(self, console: Any) -> None:
        from rich.progress import TextColumn

        failed = TextColumn("[red]{task.fields[failed]} failed")
        self._bar = progress_bar("trials", console, transient=False, extra=(failed,))
        self._task: Any = None

    def start(self, total: int, skipped: int) -> None:
        self._bar.start()
        self._task = self._bar.add_task("sweep", total=total, failed=0)
        if skipped:
            self._bar.console.print(f"{skipped} trials already done in the folder", markup=False)

    def advance(self, outcome: TrialOutcome, done: int, failed: int) -> None:
        self._bar.update(self._task, completed=done + failed, failed=failed)
        if outcome.summary is None:
            self._bar.console.print(
                f"failed: {outcome.trial.run_dir} (seed {outcome.trial.seed}): {outcome.error}",
                markup=False,
                highlight=False,
            )

    def stop(self) -> None:
        self._bar.stop()


class Preparing:
    """A sweep's progress that shows its preparation (checking every combination) until
    its trials start (:class:`tether.progress.Working`), then ``trials``'s.

    :meth:`stop` also ends the preparation's display when the sweep is refused before
    any trial.
    """

    def __init__(self, trials: TrialProgress, working: Working) -> None:
        self.trials = trials
        self.working = working.start()

    def start(self, total: int, skipped: int) -> None:
        self.working.stop()
        self.trials.start(total, skipped)

    def advance(self, outcome: TrialOutcome, done: int, failed: int) -> None:
        self.trials.advance(outcome, done, failed)

    def stop(self) -> None:
        self.working.stop()
        self.trials.stop()


def progress_for(
    console: Any, say: Callable[[str], None], preparing: str | None = None
) -> TrialProgress:
    """A progress bar when ``console`` is a terminal, else plain lines through ``say``;
    with ``preparing``, what the sweep does before its trials is shown until they start."""
    trials: TrialProgress = (
        RichProgress(console) if getattr(console, "is_terminal", False) else LineProgress(say)
    )
    if preparing is None:
        return trials
    return Preparing(trials, Working(preparing, console, say))
