"""Where the trials of a sweep run: in this process, in local processes, or on Dask.

A trial is plain data (:class:`Trial`: the scenario as a dict, its seed and its run
folder), so it crosses process and machine boundaries unchanged; the worker
re-validates the scenario and calls :func:`tether.runner.run`, which writes the run
folder atomically. Results come back as trials finish, so whatever is done is on disk
even if a later trial fails or the sweep is killed.

Executors are chosen by name (``EXECUTORS`` registry): ``serial``, ``processes``
(``concurrent.futures`` with ``workers`` processes) and ``dask`` (a ``distributed``
client: ``address`` of a running scheduler, e.g. ``tcp://10.0.0.5:8786`` started with
``dask scheduler`` / ``dask worker`` on each machine, or none for a local cluster).
"""

from __future__ import annotations

import os
import traceback
from collections.abc import Callable, Iterator
from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tether.errors import TetherError
from tether.interrupts import Stopped, raise_if_stopped, raise_on_sigterm
from tether.lifetime import die_with_parent
from tether.registry import Registry

__all__ = ["EXECUTORS", "Trial", "TrialOutcome", "check_executor", "execute", "run_trial"]


@dataclass(frozen=True)
class Trial:
    """One run of a sweep: the scenario (validated again where it runs), seed and folder.

    ``plugins`` are the ``--plugin`` modules and files to import where the trial runs
    (:func:`tether.plugins.load_plugin`), before its scenario is validated.
    """

    scenario: dict[str, Any]
    source: str
    base_dir: str
    seed: int
    run_dir: str
    plugins: tuple[str, ...] = ()


#: seconds to wait for a Dask scheduler at ``--address`` before giving up
DASK_CONNECT_TIMEOUT_S = 5.0


@dataclass(frozen=True)
class TrialOutcome:
    """A finished trial (``summary``) or a failed one (``error``, one line).

    ``internal`` is true when the failure was not a :class:`TetherError`
    (a bug, or a plug-in raising anything else); ``details`` then holds the
    traceback as text.
    """

    trial: Trial
    summary: dict[str, Any] | None
    error: str | None = None
    internal: bool = False
    details: str | None = None


def failed(trial: Trial, exc: BaseException, details: str | None = None) -> TrialOutcome:
    """The outcome of a trial that raised ``exc``: one line, internal unless a TetherError."""
    if isinstance(exc, TetherError):
        return TrialOutcome(trial, None, " ".join(str(exc).split()))
    message = " ".join(f"internal error {type(exc).__name__}: {exc}".split())
    return TrialOutcome(trial, None, message, internal=True, details=details)


def run_trial(trial: Trial) -> TrialOutcome:
    """Run one trial (in whatever process or machine the executor chose).

    Whatever the trial raises (bad input, a strategy's RuntimeError, a
    MemoryError) becomes a failed :class:`TrialOutcome`, so the sweep goes on
    with the other trials; only an interrupt (Ctrl-C) stops it.
    """
    os.environ.setdefault("MPLBACKEND", "Agg")
    from tether.config import scenario_from_dict
    from tether.plugins import load_plugins
    from tether.runner import run

    try:
        load_plugins(trial.plugins)
        scenario = scenario_from_dict(trial.scenario, trial.source, Path(trial.base_dir))
        outcome = run(scenario, out_dir=trial.run_dir, seed=trial.seed, figures=False)
    except Exception as exc:
        return failed(trial, exc, traceback.format_exc())
    return TrialOutcome(trial, outcome.summary)


Executor = Callable[[list[Trial], int, str | None], Iterator[TrialOutcome]]
EXECUTORS: Registry[Executor] = Registry("executor")


@EXECUTORS.register("serial")
def _serial(trials: list[Trial], workers: int, address: str | None) -> Iterator[TrialOutcome]:
    for trial in trials:
        yield run_trial(trial)


#: seconds between checks for a stop signal while waiting for trials
POLL_S = 0.5
#: seconds a stopped worker has to remove the run folder it was writing before it is killed
STOP_GRACE_S = 10.0


def _worker_start(parent_pid: int) -> None:
    """A worker stops cleanly on SIGTERM, leaves Ctrl-C to its parent, and dies with it
    however it dies (``kill -9`` included): no trial keeps running, and no worker waits
    forever, behind a sweep that is gone."""
    raise_on_sigterm()
    die_with_parent(parent_pid)


def _trial_in_worker(trial: Trial) -> TrialOutcome:
    try:
        return run_trial(trial)
    except Stopped as stop:  # the run folder is removed already; leave the pool's loop
        os._exit(stop.code)


def _stop_workers(pool: ProcessPoolExecutor) -> None:
    """Cancel the queued trials and stop the workers (SIGTERM, then SIGKILL after a grace)."""
    processes = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for proc in processes:
        proc.terminate()
    for proc in processes:
        proc.join(STOP_GRACE_S)
        if proc.is_alive():  # pragma: no cover (a worker stuck in C code)
            proc.kill()
            proc.join()


@EXECUTORS.register("processes")
def _processes(trials: list[Trial], workers: int, address: str | None) -> Iterator[TrialOutcome]:
    pool = ProcessPoolExecutor(
        max_workers=max(1, workers), initializer=_worker_start, initargs=(os.getpid(),)
    )
    try:
        submitted = {pool.submit(_trial_in_worker, t): t for t in trials}
        pending = set(submitted)
        while pending:
            done, pending = wait(pending, timeout=POLL_S, return_when=FIRST_COMPLETED)
            raise_if_stopped()  # a Ctrl-C that a weak-reference callback swallowed
            for future in done:
                try:
                    yield future.result()
                except Exception as exc:  # the worker process died (killed, out of memory)
                    yield failed(submitted[future], exc)
    except BaseException:  # stopped (Ctrl-C, SIGTERM) or closed early: no worker outlives it
        _stop_workers(pool)
        raise
    pool.shutdown(wait=True)


@EXECUTORS.register("dask")
def _dask(trials: list[Trial], workers: int, address: str | None) -> Iterator[TrialOutcome]:
    try:
        from distributed import Client, LocalCluster
        from distributed import wait as wait_for
    except ImportError:
        raise TetherError(
            "executor 'dask' needs dask.distributed; install it with: pip install 'tether[dask]'"
        ) from None
    cluster = None
    if address is None:  # a local cluster of processes, started and stopped here
        cluster = LocalCluster(
            n_workers=max(1, workers), threads_per_worker=1, processes=True, dashboard_address=":0"
        )
    try:
        try:
            client = Client(address or cluster, timeout=DASK_CONNECT_TIMEOUT_S)
        except (OSError, TimeoutError, ValueError, TypeError) as exc:
            reason = " ".join(str(exc).split()) or type(exc).__name__
            raise TetherError(
                f"--address {address}: no Dask scheduler answered within "
                f"{DASK_CONNECT_TIMEOUT_S:g} s ({reason[:120]}); start `dask scheduler` there "
                "or check the address, e.g. tcp://HOST:8786"
            ) from None
        with client:
            futures = client.map(run_trial, trials, pure=False)
            trial_of = {f.key: t for f, t in zip(futures, trials, strict=True)}
            pending = set(futures)
            while pending:
                try:
                    done, pending = wait_for(pending, timeout=POLL_S, return_when="FIRST_COMPLETED")
                except TimeoutError:  # distributed's wait raises when nothing finished in time
                    done = set()
                raise_if_stopped()  # a Ctrl-C that a weak-reference callback swallowed
                for future in done:
                    try:
                        yield future.result()
                    except Exception as exc:  # the worker died or the scheduler went away
                        yield failed(trial_of[future.key], exc)
    finally:
        if cluster is not None:
            cluster.close()


def execute(
    trials: list[Trial],
    executor: str = "serial",
    *,
    workers: int | None = None,
    address: str | None = None,
) -> Iterator[TrialOutcome]:
    """Run ``trials`` on the named executor, yielding each outcome as it finishes."""
    n = check_executor(executor, workers, address)
    return EXECUTORS.get(executor)(trials, n, address)


def check_executor(executor: str, workers: int | None = None, address: str | None = None) -> int:
    """Refuse an unknown executor, a bad worker count or a stray address; the worker count."""
    if executor not in EXECUTORS:
        raise TetherError(
            f"unknown executor {executor!r}; expected one of: {', '.join(EXECUTORS.names())}"
        )
    if workers is not None and (
        isinstance(workers, bool) or not isinstance(workers, int) or workers < 1
    ):
        raise ValueError(f"workers must be a positive integer or None (got {workers!r})")
    if address is not None and executor != "dask":
        raise TetherError(
            f"--address {address}: only the dask executor uses a scheduler address; "
            "add --executor dask or drop --address"
        )
    return workers if workers is not None else (os.cpu_count() or 1)
