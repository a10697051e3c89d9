"""No process outlives the command: kernels compile inside the command that needs them.

With ``TETHER_JIT=auto`` and a cold numba cache, the process that needs the kernels
compiles them in a child it waits for (a line on stderr says so), then uses them; the
child dies with it, even on ``kill -9``. Nothing is left running once tether exits. The
compiler is replaced here by a small stand-in (the real one takes a minute or more):
what is tested is who waits for it and when it ends.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

STAND_IN = textwrap.dedent(
    """
    import os, sys, time
    open({pid_file!r}, "w").write(str(os.getpid()))
    time.sleep({sleep_s})
    open(sys.argv[-1], "w").write("compiled")
    """
)

PARENT = textwrap.dedent(
    """
    import sys
    from tether import jit
    jit.COMPILE_COMMAND = [sys.executable, "-c", {stand_in!r}]
    print("enabled", jit.enabled(), flush=True)
    """
)


def alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    with open(f"/proc/{pid}/stat") as fh:  # a zombie is gone but for its exit status
        return fh.read().split(") ", 1)[1][0] != "Z"


def start(tmp_path: Path, sleep_s: float) -> tuple[subprocess.Popen, Path]:
    pid_file = tmp_path / "child.pid"
    stand_in = STAND_IN.format(pid_file=str(pid_file), sleep_s=sleep_s)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"), TETHER_JIT="auto",
               TETHER_JIT_AFTER_S="0")  # fmt: skip
    (tmp_path / "cache").mkdir()
    proc = subprocess.Popen(
        [sys.executable, "-c", PARENT.format(stand_in=stand_in)],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    return proc, pid_file


def wait_for(path: Path, timeout_s: float = 60.0) -> None:
    end = time.monotonic() + timeout_s
    while not (path.exists() and path.read_text()):
        assert time.monotonic() < end, f"{path} never appeared"
        time.sleep(0.05)


def test_a_cold_cache_is_compiled_inside_the_command_and_nothing_is_left(tmp_path):
    proc, pid_file = start(tmp_path, sleep_s=1.0)
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    assert "enabled True" in out  # waited for the compiler, then used the kernels
    assert "compiling the numba kernels once" in err and "kernels compiled in" in err
    child = int(pid_file.read_text())
    assert not alive(child)  # the compiler ended before the command did
    assert not list((tmp_path / "cache").glob("*.lock"))


def test_the_compiler_dies_with_a_killed_command(tmp_path):
    proc, pid_file = start(tmp_path, sleep_s=600.0)
    wait_for(pid_file)
    child = int(pid_file.read_text())
    assert alive(child)
    proc.send_signal(signal.SIGKILL)
    proc.communicate(timeout=30)
    end = time.monotonic() + 10
    while alive(child) and time.monotonic() < end:
        time.sleep(0.1)
    assert not alive(child), "the compiler outlived a kill -9 of its command"


def test_a_warm_cache_compiles_nothing(tmp_path):
    """The marker says the cache holds the kernels: no child, no line."""
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path), TETHER_JIT="auto",
               TETHER_JIT_AFTER_S="0")  # fmt: skip
    code = "from tether import jit; print(jit.marker())"
    marker = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                            text=True, check=True).stdout.strip()  # fmt: skip
    Path(marker).write_text("warm-up 1.0 s\n")
    parent = PARENT.format(stand_in="raise SystemExit(3)")
    run = subprocess.run([sys.executable, "-c", parent], capture_output=True, text=True,
                         env=env, timeout=60)  # fmt: skip
    assert "enabled True" in run.stdout and "compiling" not in run.stderr
