"""Files written whole or not at all, never through a link, under names safe from data.

Every file tether writes goes through :func:`atomic_write`: the content is written to a
temporary name beside the target and renamed onto it, so a reader (or a full disk, or a
kill) never leaves half a file at the target; a symbolic link or a folder at the target
is refused, so tether never writes through a link to a file elsewhere. A file name taken
from data (a scenario's name) goes through :func:`safe_file_name` first.
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from collections.abc import Callable
from pathlib import Path

from tether.errors import OutputError

__all__ = ["UMASK", "atomic_write", "check_output_path", "safe_file_name"]

UMASK = os.umask(0)
os.umask(UMASK)

#: the longest file name :func:`safe_file_name` gives, in bytes (file systems allow 255)
MAX_NAME_BYTES = 120


def check_output_path(path: Path) -> None:
    """Refuse (:class:`OutputError`) an output file path that is a link or a folder."""
    if path.is_symlink():
        raise OutputError(
            f"{path}: is a symbolic link; tether does not write through links (remove the "
            "link or choose another output path)"
        )
    if path.is_dir():
        raise OutputError(f"{path}: is a folder; give a file path or another --out")


def atomic_write(path: Path, write: Callable[[str], None]) -> None:
    """Call ``write(tmp)`` on a temporary file beside ``path``, then rename it onto ``path``.

    A symbolic link or a folder at ``path`` is refused (:class:`OutputError`): tether never
    writes through a link to a file elsewhere, nor replaces a link the user made. If
    ``write`` fails (a full disk), the temporary file is removed and ``path`` is as it was.
    """
    check_output_path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name[:100]}.", suffix=".tmp")
    os.close(fd)
    try:
        write(tmp)
        os.chmod(tmp, 0o666 & ~UMASK)  # mkstemp makes 0600; results are ordinary files
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def safe_file_name(text: str, fallback: str = "run") -> str:
    """``text`` as one file name: no path separators, no leading dot, printable, short.

    A name that had to change keeps its readable start and gets a short hash of the
    original, so two different names stay different.
    """
    cleaned = "".join(c if c.isprintable() and c not in "/\\\x00:" else "_" for c in str(text))
    cleaned = cleaned.strip().lstrip(".") or fallback
    if cleaned == text and len(cleaned.encode()) <= MAX_NAME_BYTES:
        return cleaned
    digest = hashlib.sha1(str(text).encode("utf-8", "surrogatepass")).hexdigest()[:8]
    head = cleaned.encode()[: MAX_NAME_BYTES - 10].decode("utf-8", "ignore").rstrip()
    return f"{head}~{digest}"
