"""What ``tether animate``, ``tether view`` and ``tether export`` do (the CLI is a thin layer)."""

from __future__ import annotations

import time
from pathlib import Path
from typing import Any

from tether.viewing.runfolder import load_run


def _mb(n_bytes: int) -> str:
    return f"{n_bytes / 1e6:.2f} MB"


def animate_command(
    run_dir: Path,
    out: Path | None,
    *,
    fmt: str | None,
    fps: float,
    duration_s: float | None,
    stride: int | None,
    width_px: int,
    say: Any,
    progress: bool = True,
) -> Path:
    from tether.viewing.animate import animate

    result = animate(
        run_dir,
        out,
        fmt=fmt,
        fps=fps,
        duration_s=duration_s,
        stride=stride,
        width_px=width_px,
        progress=progress,
    )
    say(
        f"animation: {result.path} ({result.format}, {result.n_frames} frames, "
        f"{result.size_px[0]}x{result.size_px[1]} px, {_mb(result.bytes)}, "
        f"{result.seconds:.1f} s)"
    )
    return result.path


def view_command(
    run_dir: Path,
    out: Path | None,
    *,
    max_mb: float,
    serve: bool,
    port: int,
    say: Any,
) -> Path:
    from tether.errors import TetherError
    from tether.viewing.replay import bind_server, write_replay
    from tether.viewing.replay import serve as serve_file

    if max_mb <= 0:
        raise TetherError(f"--max-mb: must be positive (got {max_mb})")
    start = time.perf_counter()
    server = bind_server(port) if serve else None  # a port in use is refused before any work
    try:
        run = load_run(run_dir)
        for note in run.notes:
            say(f"note: {note}")
        result = write_replay(run, out, budget_bytes=int(max_mb * 1e6))
    except BaseException:
        if server is not None:
            server.server_close()
        raise
    thinned = f", 1 in {result.stride} recorded steps" if result.stride > 1 else ""
    say(
        f"replay: {result.path} ({_mb(result.bytes)}, {result.n_frames} frames{thinned}, "
        f"{time.perf_counter() - start:.1f} s)"
    )
    if server is not None:
        serve_file(result.path, port, announce=say, server=server)
    return result.path


def export_command(run_dir: Path, out: Path | None, *, fmt: str, say: Any) -> Path:
    from tether.export.ros2 import export
    from tether.progress import progress_bar

    run = load_run(run_dir)
    with progress_bar("writing steps") as bar:
        task = bar.add_task("export", total=run.n_frames)
        result = export(run, out, fmt=fmt, progress=lambda k: bar.advance(task, k))
    total = sum(result.messages.values())
    say(
        f"{result.format}: {result.path} ({total} messages on {len(result.messages)} topics, "
        f"{_mb(result.bytes)}, {result.seconds:.1f} s)"
    )
    for topic in ("/tether/robots", "/tether/links", "/map", "/tether/obstacles"):
        if topic in result.messages:
            say(f"  {topic:<24} {result.messages[topic]}")
    return result.path
