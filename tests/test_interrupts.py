"""Ctrl-C and SIGTERM stop `tether run` and `tether sweep` as they stop Unix tools.

Each test starts the real command in its own process, waits until it is demonstrably
in the middle of its work (a run folder being staged; a sweep with one trial finished
and another being written), sends the signal, and checks: exit code 128 + signal
(130, 143), one line on stderr, no half-written folder, finished trials kept, and no
worker process left behind.
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
import yaml

from tether import interrupts
from tether.config import load_scenario, scenario_from_dict
from tether.experiments.sweep import run_sweep
from tether.interrupts import Stopped, stop_on_signals
from tether.paths.trajectory import Polyline
from tether.runfolder import RunFolder
from tether.sensing import SensorModel
from tether.silent import SilentStrategy
from tether.sim import TeamState, simulate
from tether.world import World

#: a hang guard, not a timing: the command must stop long before this
DEADLINE_S = 120.0
#: a team that is never done: its leader heads 100 km east (the run would take minutes)
LONG = ["--set", "sim.max_steps=100000",
        "--set", "strategy.params.trajectory.waypoints=[[0,0],[100000,0]]"]  # fmt: skip
SIGNALS = [(signal.SIGINT, 130, "SIGINT (Ctrl-C)"), (signal.SIGTERM, 143, "SIGTERM")]


def _start(args: list[str], cwd: Path) -> subprocess.Popen:
    env = dict(os.environ, TETHER_JIT="0", COLUMNS="200")
    code = "import sys; from tether.cli import main; sys.argv[0] = 'tether'; main()"
    return subprocess.Popen([sys.executable, "-c", code, *args], cwd=cwd, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True)  # fmt: skip


def _kill_all(proc: subprocess.Popen) -> tuple[str, str]:
    """Kill the command and every process it started (its own process group)."""
    with contextlib.suppress(ProcessLookupError):
        os.killpg(proc.pid, signal.SIGKILL)
    return proc.communicate()


def _wait_for(proc: subprocess.Popen, ready) -> None:
    start = time.monotonic()
    while not ready():
        if proc.poll() is not None:
            out, err = proc.communicate()
            pytest.fail(f"the command ended before it could be interrupted: {out} {err}")
        if time.monotonic() - start > DEADLINE_S:
            _kill_all(proc)
            pytest.fail("the command never reached the point to interrupt")
        time.sleep(0.05)


def _stop(proc: subprocess.Popen, signum: int) -> tuple[int, str, str]:
    """Ctrl-C as a terminal sends it (to the whole process group); SIGTERM as ``kill PID``."""
    if signum == signal.SIGINT:
        os.killpg(proc.pid, signum)
    else:
        proc.send_signal(signum)
    try:
        out, err = proc.communicate(timeout=DEADLINE_S)
    except subprocess.TimeoutExpired:
        out, err = _kill_all(proc)
        pytest.fail(f"still running {DEADLINE_S:g} s after the signal: {err[-500:]}")
    return proc.returncode, out, err


def _staging(folder: Path) -> list[Path]:
    return [p for p in folder.rglob("*") if ".staging-" in p.name]


def _processes_naming(text: str) -> list[int]:
    """Live processes whose command line holds ``text`` (workers carry their parent's)."""
    found = []
    for proc in Path("/proc").glob("[0-9]*"):
        try:
            cmdline = (proc / "cmdline").read_bytes().replace(b"\0", b" ").decode()
            state = (proc / "stat").read_text().split(")")[-1].split()[0]
        except OSError:
            continue
        if text in cmdline and state != "Z":
            found.append(int(proc.name))
    return found


@pytest.mark.parametrize(("signum", "code", "name"), SIGNALS, ids=["SIGINT", "SIGTERM"])
def test_run_stops_with_one_line_and_leaves_no_folder(tmp_path, signum, code, name) -> None:
    proc = _start(["run", "silent_demo", "--out", "out/r", *LONG], tmp_path)
    _wait_for(proc, lambda: bool(_staging(tmp_path)))  # simulating into its staged folder
    exit_code, out, err = _stop(proc, signum)
    assert exit_code == code
    assert err.splitlines() == [f"interrupted by {name}: no run folder was written"]
    assert "Traceback" not in out + err
    assert list(tmp_path.iterdir()) == [], "a half-written run folder was left behind"


@pytest.mark.skipif(not Path("/proc").is_dir(), reason="finds worker processes in /proc")
@pytest.mark.parametrize(("signum", "code", "name"), SIGNALS, ids=["SIGINT", "SIGTERM"])
def test_sweep_stops_workers_keeps_finished_trials(tmp_path, signum, code, name) -> None:
    data = load_scenario("silent_demo").model_dump(mode="json")
    data["output"]["figures"] = False
    data["strategy"]["params"]["trajectory"]["waypoints"] = [[0, 0], [100000, 0]]
    data["sweep"] = {"sim.max_steps": [3, 100000]}  # one quick trial, one that never ends
    (tmp_path / "long.yaml").write_text(yaml.safe_dump(data))
    sweep_dir = tmp_path / "sweep"
    proc = _start(["sweep", "long.yaml", "--out", str(sweep_dir), "--workers", "2"], tmp_path)
    quick = next(iter(sweep_dir.glob("max_steps=3*/seed-*/summary.json")), None)

    def one_done_one_running() -> bool:
        nonlocal quick
        quick = next(iter(sweep_dir.glob("max_steps=3*/seed-*/summary.json")), None)
        return quick is not None and bool(_staging(sweep_dir))

    _wait_for(proc, one_done_one_running)
    exit_code, out, err = _stop(proc, signum)
    assert exit_code == code
    assert err.splitlines() == [
        f"interrupted by {name}: finished trials are kept in {sweep_dir}; "
        "the same command resumes the sweep"
    ]
    assert _processes_naming(str(sweep_dir)) == [], "a worker process outlived the sweep"
    assert _staging(sweep_dir) == [], "a half-written trial folder was left behind"
    assert quick.is_file(), "the finished trial was lost"
    runs = {p.parent for p in sweep_dir.rglob("scenario.yaml")}
    assert runs == {quick.parent}, "a trial folder without its summary was left behind"


def test_ctrl_c_ends_view_serve_normally(tmp_path) -> None:
    """Serving a replay lasts until Ctrl-C: that is its normal end (exit 0)."""
    import socket
    import urllib.request

    from _viewing_helpers import make_run_folder

    make_run_folder(tmp_path / "run", n_steps=5)
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    proc = _start(["view", "run", "--serve", "--port", str(port)], tmp_path)

    def serving() -> bool:  # answered by the serving thread, not just a bound socket
        try:
            with urllib.request.urlopen(f"http://127.0.0.1:{port}/", timeout=5) as reply:
                return reply.status == 200
        except OSError:
            return False

    _wait_for(proc, serving)
    exit_code, out, err = _stop(proc, signal.SIGINT)
    assert exit_code == 0, err
    assert "serving" in out and err == ""


class _SignalsWhileCollected:
    """Sends ``signum`` to its own process from ``__del__``: the handler's exception is
    raised where Python only prints "Exception ignored" and carries on."""

    def __init__(self, signum: int) -> None:
        self.signum = signum

    def __del__(self) -> None:
        signal.raise_signal(self.signum)


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
@pytest.mark.parametrize(("signum", "code", "name"), SIGNALS)
def test_a_stop_swallowed_by_a_finalizer_stops_the_next_step(signum, code, name) -> None:
    strategy = SilentStrategy(d_max_m=15.0, trajectory=Polyline([[0, 0], [1000, 0]]))
    start = TeamState.at_rest(np.array([[0.0, 0.0], [5.0, 0.0]]))
    with pytest.raises(Stopped) as stop, stop_on_signals():
        _SignalsWhileCollected(signum)  # collected at once: the stop is swallowed there
        simulate(World(dim=2), SensorModel(15.0), strategy, start,
                 dt_s=0.1, max_steps=50, rng=np.random.default_rng(0))  # fmt: skip
    assert (stop.value.code, str(stop.value)) == (code, f"interrupted by {name}")
    # the stop was handled: the next block runs to its end
    with stop_on_signals():
        result = simulate(World(dim=2), SensorModel(15.0), strategy, start,
                          dt_s=0.1, max_steps=5, rng=np.random.default_rng(0))  # fmt: skip
    assert result.steps == 5


@pytest.mark.filterwarnings("ignore::pytest.PytestUnraisableExceptionWarning")
def test_a_stop_swallowed_while_writing_keeps_the_run_folder_out(tmp_path) -> None:
    folder = RunFolder(tmp_path / "run")
    with pytest.raises(Stopped), stop_on_signals():
        folder.write_json("part.json", {"written": True})
        _SignalsWhileCollected(signal.SIGINT)  # swallowed between two writes
        folder.commit({"ok": True})
    folder.abort()
    assert not (tmp_path / "run").exists()


@pytest.mark.timeout(120)
@pytest.mark.parametrize("executor", ["processes", "dask"])
def test_a_swallowed_stop_ends_a_sweep_s_wait_for_its_workers(executor, tmp_path) -> None:
    """The state a finalizer leaves behind (a stop recorded, its exception swallowed) while
    the sweep waits on a trial that never ends: the wait must end with :class:`Stopped`."""
    if executor == "dask":
        pytest.importorskip("distributed")
    data = load_scenario("silent_demo").model_dump(mode="json")
    data["output"]["figures"] = False
    data["strategy"]["params"]["trajectory"]["waypoints"] = [[0, 0], [100000, 0]]
    data["sim"]["max_steps"] = 100000
    swallowed = threading.Timer(2.0, interrupts._record, args=(signal.SIGINT,))  # noqa: SLF001
    with pytest.raises(Stopped) as stop, stop_on_signals():
        swallowed.start()
        run_sweep(scenario_from_dict(data, "long.yaml"), tmp_path / "sweep", seeds=1,
                  executor=executor, workers=1)  # fmt: skip
    swallowed.join()
    assert stop.value.code == 130
