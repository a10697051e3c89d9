"""One sweep at a time per sweep folder: a lock held for the whole sweep.

``tether sweep`` takes an exclusive lock on ``<out>/.tether-sweep.lock`` (``flock``)
before it reads or writes anything in the folder and keeps it until its table is
written. A second sweep into the same folder is refused in one line, at once, naming the
process that holds it; the operating system releases the lock when its holder ends in
any way (``kill -9`` included), so a killed sweep never blocks its resume. Under the lock,
the sweep removes what a killed sweep left: staging folders of unfinished trials and
temporary files of interrupted writes.
"""

from __future__ import annotations

import os
import shutil
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from tether.errors import OutputError

try:  # POSIX
    import fcntl
except ImportError:  # pragma: no cover - Windows: sweeps are not locked
    fcntl = None  # type: ignore[assignment]

__all__ = ["LOCK_FILE", "clean_leftovers", "sweep_lock"]

#: the lock file inside a sweep folder (tether's own; an otherwise empty folder with it is new)
LOCK_FILE = ".tether-sweep.lock"


@contextmanager
def sweep_lock(out: Path) -> Iterator[None]:
    """Hold the sweep lock of folder ``out`` (which must exist) for the ``with`` block.

    Raises
    ------
    OutputError
        Another process holds it: one line naming its process id and the fix.
    """
    path = out / LOCK_FILE
    try:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError as exc:
        raise OutputError(
            f"{out}: cannot write the sweep folder ({exc.strerror or exc}); choose a writable --out"
        ) from None
    try:
        if fcntl is not None:
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = os.pread(fd, 32, 0).decode(errors="replace").strip() or "?"
                raise OutputError(
                    f"{out}: another tether sweep (process {holder}) is running in this folder; "
                    "wait for it to finish (it resumes nothing twice), or choose another --out"
                ) from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        yield
    finally:
        os.close(fd)  # releases the lock


def clean_leftovers(out: Path) -> int:
    """Remove what killed sweeps left in ``out``; call it only under :func:`sweep_lock`.

    Staging and replaced folders of run folders (``.<name>.staging-*``, ``.<name>.old-*``)
    in the combination folders, and temporary files of interrupted atomic writes
    (``.<name>.*.tmp``) in the folder, its combination folders and ``figures/``. Nothing
    else is touched. Returns how many entries were removed.
    """
    removed = 0
    folders = [out, *(p for p in out.iterdir() if p.is_dir() and not p.is_symlink())]
    for folder in folders:
        for entry in folder.iterdir():
            name = entry.name
            if not name.startswith("."):
                continue
            if (
                entry.is_dir()
                and not entry.is_symlink()
                and (".staging-" in name or ".old-" in name)
            ):
                shutil.rmtree(entry, ignore_errors=True)
                removed += 1
            elif name.endswith(".tmp") and entry.is_file() and not entry.is_symlink():
                entry.unlink(missing_ok=True)
                removed += 1
    return removed
