"""Where ``tether view``, ``animate`` and ``export`` write: whole files, never through a link.

Each output is written to a temporary name beside its target and renamed onto it
(:func:`tether.atomic.atomic_write`), so a full disk or a kill leaves the previous file or
none, never a truncated page or a 0-byte GIF; a link at the target is refused, not
followed; a disk that cannot be written becomes one line naming the path. An output
written into a run folder is added to the folder's marker (it is tether's file).
"""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Callable
from pathlib import Path

from tether.atomic import atomic_write, check_output_path
from tether.errors import OutputError
from tether.runfolder import record_output

__all__ = ["check_target", "write_output", "write_output_folder"]


def _refused(path: Path, what: str, exc: OSError) -> OutputError:
    return OutputError(
        f"{path}: cannot write the {what} ({exc.strerror or exc}); free some space or "
        "choose a writable --out"
    )


def check_target(path: Path) -> None:
    """Refuse a link or a folder at an output file path before any work is done."""
    check_output_path(path)


def _record(path: Path, run_dir: Path | None) -> None:
    if run_dir is None:
        return
    try:
        if path.parent.resolve() == Path(run_dir).resolve():
            record_output(Path(run_dir), path.name)
    except OSError:  # the output is written; the marker only helps a later --out
        pass


def write_output(
    path: Path, write: Callable[[str], None], *, what: str, run_dir: Path | None = None
) -> int:
    """Write a file with ``write(tmp)`` atomically; its size in bytes.

    Raises
    ------
    OutputError
        A link or a folder at ``path``; a folder or disk that cannot be written
        (read-only, full): one line, and ``path`` is as it was.
    """
    try:
        atomic_write(path, write)
        size = path.stat().st_size
    except OSError as exc:
        raise _refused(path, what, exc) from None
    _record(path, run_dir)
    return size


def write_output_folder(
    path: Path, write: Callable[[Path], None], *, what: str, run_dir: Path | None = None
) -> int:
    """Write a new folder with ``write(tmp_folder)`` (which must create it) and rename it
    onto ``path``, which must not exist; its size in bytes."""
    if path.is_symlink() or path.exists():
        raise OutputError(f"{path}: already exists; {what} writes a new folder (remove it first)")
    staging = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        staging = Path(tempfile.mkdtemp(dir=path.parent, prefix=f".{path.name[:100]}.staging-"))
        inner = staging / path.name
        write(inner)
        os.rename(inner, path)
        size = sum(f.stat().st_size for f in path.rglob("*") if f.is_file())
    except OSError as exc:
        raise _refused(path, what, exc) from None
    finally:
        if staging is not None:
            shutil.rmtree(staging, ignore_errors=True)
    _record(path, run_dir)
    return size
