"""Result files written like a database commit, and the provenance recorded with them.

Every file is written to a temporary name beside its target and renamed into
place (:func:`atomic_write`), so nobody ever reads half a file. A run folder
(:class:`RunFolder`) goes further: all its files are written into a hidden
staging folder beside the target, ``summary.json`` last, and the staging
folder is then renamed onto the target. A run killed at any moment leaves the
previous complete folder or nothing at its path, never a mix of two runs, and
a folder holding ``summary.json`` always holds everything else too.
"""

from __future__ import annotations

import datetime as dt
import json
import os
import platform
import shutil
import subprocess
import tempfile
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import scipy
import yaml

from tether import __version__
from tether.atomic import UMASK
from tether.atomic import atomic_write as atomic_write  # re-exported
from tether.atomic import check_output_path as check_output_path  # re-exported
from tether.errors import OutputError
from tether.interrupts import raise_if_stopped

SUMMARY = "summary.json"
SCENARIO = "scenario.yaml"
#: the file that marks a folder as a tether run folder; only tether writes it
MARKER = ".tether-run.json"
#: the marker formats this version of tether reads
MARKER_FORMAT = 1
_MARKER_KIND = "tether run folder"
_MARKER_MAX_BYTES = 1 << 20


def jsonable(value: Any) -> Any:
    """``value`` with numpy scalars/arrays as Python values and non-finite floats as null/"inf"."""
    if isinstance(value, dict):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [jsonable(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, np.ndarray):
        return jsonable(value.tolist())
    if isinstance(value, float) and not np.isfinite(value):
        return None if np.isnan(value) else ("inf" if value > 0 else "-inf")
    return value


def write_json(path: Path, data: dict[str, Any]) -> Path:
    def write(tmp: str) -> None:
        with open(tmp, "w") as fh:
            json.dump(jsonable(data), fh, indent=2)
            fh.write("\n")

    atomic_write(path, write)
    return path


def write_yaml(path: Path, data: dict[str, Any]) -> Path:
    def write(tmp: str) -> None:
        with open(tmp, "w") as fh:
            yaml.safe_dump(jsonable(data), fh, sort_keys=False)

    atomic_write(path, write)
    return path


def write_table(path: Path, columns: dict[str, Any]) -> Path:
    """Columns (equal-length sequences) as a Parquet table."""
    table = pa.table({k: pa.array(np.asarray(v)) for k, v in columns.items()})
    atomic_write(path, lambda tmp: pq.write_table(table, tmp))
    return path


def write_rows(path: Path, rows: list[dict[str, Any]]) -> Path:
    """A list of dicts (possibly with differing keys) as a Parquet table."""
    if rows:
        keys = list(dict.fromkeys(k for r in rows for k in r))
        cols = {k: [jsonable(r.get(k)) for r in rows] for k in keys}
        table = pa.table({k: _column(v) for k, v in cols.items()})
    else:
        table = pa.table({"step": pa.array([], pa.int64()), "kind": pa.array([], pa.string())})
    atomic_write(path, lambda tmp: pq.write_table(table, tmp))
    return path


def _column(values: list[Any]) -> pa.Array:
    """One table column; values of mixed types (``15.0`` and ``'15.0'``) become text."""
    try:
        return pa.array(values)
    except (pa.ArrowInvalid, pa.ArrowTypeError, pa.ArrowNotImplementedError, OverflowError):
        return pa.array([None if v is None else json.dumps(v) for v in values], pa.string())


def save_figure(fig: Any, path: Path, dpi: int = 120) -> Path:
    """Write a matplotlib figure as PNG (atomically) and close it."""
    try:
        atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=dpi, format="png"))
    finally:
        import matplotlib.pyplot as plt  # loaded already: the figure exists

        plt.close(fig)  # long sweeps would otherwise keep every figure alive
    return path


def read_marker(path: Path) -> dict[str, Any] | None:
    """The run-folder marker of ``path`` (:data:`MARKER`), or None if it has no valid one.

    Only a regular file written by tether counts: a JSON object of this kind, of a
    format this version reads, with the tether version and the list of entries tether
    wrote into the folder.
    """
    file = path / MARKER
    try:
        if file.is_symlink() or not file.is_file() or file.stat().st_size > _MARKER_MAX_BYTES:
            return None
        data = json.loads(file.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return None
    if (
        not isinstance(data, dict)
        or data.get("kind") != _MARKER_KIND
        or data.get("format") != MARKER_FORMAT
        or not isinstance(data.get("tether_version"), str)
        or not isinstance(data.get("files"), list)
        or not all(isinstance(f, str) for f in data["files"])
    ):
        return None
    return data


def is_run_folder(path: Path) -> bool:
    """A folder tether wrote for a run: it holds tether's marker (:func:`read_marker`)."""
    return read_marker(path) is not None


def _marker(files: list[str]) -> dict[str, Any]:
    return {
        "kind": _MARKER_KIND,
        "format": MARKER_FORMAT,
        "tether_version": __version__,
        "files": sorted(set(files)),
    }


def _is_leftover(name: str) -> bool:
    """A temporary file of an interrupted atomic write (:func:`atomic_write`)."""
    return name.startswith(".") and name.endswith(".tmp")


def foreign_entries(path: Path) -> list[str]:
    """Entries of run folder ``path`` that tether did not write (its marker does not list)."""
    marker = read_marker(path)
    known = set(marker["files"]) if marker is not None else set()
    names = sorted(entry.name for entry in os.scandir(path))
    return [n for n in names if n != MARKER and n not in known and not _is_leftover(n)]


def record_output(run_dir: Path, name: str) -> None:
    """Add ``name`` (a file tether just wrote into ``run_dir``) to the run folder's marker.

    ``tether view``, ``animate`` and ``export`` call this, so that a later ``--out`` onto
    the folder knows those files are tether's too. Nothing happens outside a run folder.
    """
    marker = read_marker(run_dir)
    if marker is not None and name not in marker["files"]:
        write_json(run_dir / MARKER, _marker([*marker["files"], name]))


def check_replaceable(path: Path) -> None:
    """Refuse (:class:`OutputError`) a ``--out`` that a run folder commit may not replace.

    Allowed: nothing there, an empty folder, or a tether run folder (:data:`MARKER`)
    holding only what tether wrote. Everything else is refused and left untouched.
    """
    if path.is_symlink():
        raise OutputError(
            f"{path}: is a symbolic link; give the folder itself or a new --out (tether "
            "replaces only its own run folders)"
        )
    if not path.exists():
        return
    if not path.is_dir():
        raise OutputError(f"{path}: exists and is not a folder; choose another --out")
    if not any(path.iterdir()):
        return
    if not is_run_folder(path):
        raise OutputError(
            f"{path}: folder is not empty and not a tether run folder (it has no {MARKER} "
            "marker); choose a new or empty folder for --out (tether replaces only its own run "
            "folders)"
        )
    foreign = foreign_entries(path)
    if foreign:
        raise OutputError(
            f"{path}: holds {foreign[0]!r}{' and more' if len(foreign) > 1 else ''}, which "
            "tether did not write; move it out of the run folder or choose another --out"
        )


def check_writable(folder: str | Path) -> None:
    """Refuse (:class:`OutputError`) a folder that run folders could not be created in.

    Creates what is missing and a temporary folder inside, then removes all of it:
    nothing is left, whatever the answer.
    """
    folder = Path(folder)
    created: list[Path] = []
    try:
        here = folder.absolute()
        while not here.exists() and here != here.parent:
            created.append(here)
            here = here.parent
        folder.mkdir(parents=True, exist_ok=True)
        os.rmdir(tempfile.mkdtemp(dir=folder, prefix=".tether-check-"))
    except OSError as exc:
        raise OutputError(
            f"{folder}: cannot create run folders here ({exc.strerror or exc}); choose a "
            "writable output.dir or --out"
        ) from None
    finally:
        for path in created:  # deepest first
            try:
                path.rmdir()
            except OSError:
                break


class RunFolder:
    """The files of one run, staged and committed as a whole (see the module docstring).

    Parameters
    ----------
    path
        The run folder. If it exists it must be empty or a tether run folder
        (which the commit replaces); anything else is refused, so that
        ``--out .`` can never delete a user's files.
    """

    def __init__(self, path: str | Path) -> None:
        self.path = Path(path)
        # every operation works on the absolute path: ``--out .`` inside a run folder
        # stages beside it, in the real parent, never inside the folder being replaced
        self._target = Path(os.path.abspath(self.path))
        self._created: list[Path] = []  # parent folders made here, removed again on abort
        try:
            check_replaceable(self._target)
            parent = self._target.parent
            while not parent.exists() and parent != parent.parent:
                self._created.append(parent)
                parent = parent.parent
            self.staging = self._make_staging()
        except OSError as exc:
            self._remove_created()
            raise OutputError(
                f"{self.path}: cannot create the run folder ({exc.strerror or exc}); "
                "choose a writable --out"
            ) from None
        os.chmod(self.staging, 0o777 & ~UMASK)
        self.written: list[str] = []

    def _make_staging(self, tries: int = 5) -> Path:
        """The staging folder beside :attr:`path`, its parents made as needed.

        In a sweep, another trial's run folder in the same parent may be aborted at the
        same moment and remove the parent it made (:meth:`abort`) between our ``mkdir``
        and ``mkdtemp``: then the parent is made again.
        """
        prefix = f".{self._target.name}.staging-"
        parent = self._target.parent
        for _ in range(tries - 1):
            parent.mkdir(parents=True, exist_ok=True)
            try:
                return Path(tempfile.mkdtemp(dir=parent, prefix=prefix))
            except FileNotFoundError:
                continue
        parent.mkdir(parents=True, exist_ok=True)
        return Path(tempfile.mkdtemp(dir=parent, prefix=prefix))

    def _remove_created(self) -> None:
        for folder in self._created:  # deepest first
            try:
                folder.rmdir()
            except OSError:
                break

    def file(self, name: str) -> Path:
        self.written.append(name)
        return self.staging / name

    def write_yaml(self, name: str, data: dict[str, Any]) -> Path:
        return write_yaml(self.file(name), data)

    def write_json(self, name: str, data: dict[str, Any]) -> Path:
        return write_json(self.file(name), data)

    def write_table(self, name: str, columns: dict[str, Any]) -> Path:
        return write_table(self.file(name), columns)

    def write_rows(self, name: str, rows: list[dict[str, Any]]) -> Path:
        return write_rows(self.file(name), rows)

    def save_figure(self, fig: Any, name: str, dpi: int = 120) -> Path:
        return save_figure(fig, self.file(f"figures/{name}"), dpi)

    def commit(self, summary: dict[str, Any]) -> Path:
        """Write the marker, ``summary.json`` last, and move the staged folder onto :attr:`path`.

        The folder at :attr:`path` is checked again first (a user may have put a file into
        it while the run was simulating): anything tether did not write stops the commit,
        and so does a stop signal that was swallowed while the folder was being written.
        """
        raise_if_stopped()
        tops = [name.split("/", 1)[0] for name in [*self.written, SUMMARY]]
        write_json(self.staging / MARKER, _marker(tops))
        write_json(self.file(SUMMARY), summary)
        target = self._target
        check_replaceable(target)
        old = None
        if target.exists():
            old = Path(tempfile.mkdtemp(dir=target.parent, prefix=f".{target.name}.old-"))
            os.replace(target, old / "run")
        os.replace(self.staging, target)
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
        return self.path

    def abort(self) -> None:
        """Drop everything staged (the target folder is left as it was).

        Parent folders created for the run are removed again if still empty, so a
        failed run leaves nothing behind.
        """
        shutil.rmtree(self.staging, ignore_errors=True)
        self._remove_created()


def git_hash() -> str:
    """The git commit of tether's source: the checkout's ``HEAD`` when tether runs from
    one, else the commit its package was built from (``build_commit.txt``, written at
    build time), else ``"unknown"``. A checkout that merely contains an installed tether
    (a virtual environment inside another project) is not mistaken for its source."""
    here = Path(__file__).parent
    try:
        tracked = subprocess.run(["git", "ls-files", "--error-unmatch", "__init__.py"],
                                 cwd=here, capture_output=True, timeout=5)  # fmt: skip
        if tracked.returncode == 0:
            out = subprocess.run(["git", "rev-parse", "HEAD"], cwd=here, capture_output=True,
                                 text=True, timeout=5)  # fmt: skip
            if out.returncode == 0 and out.stdout.strip():
                return out.stdout.strip()
    except (OSError, subprocess.TimeoutExpired):
        pass
    try:
        return (here / "build_commit.txt").read_text().strip() or "unknown"
    except OSError:
        return "unknown"


def provenance() -> dict[str, Any]:
    """Package version, git hash and machine, recorded with every result."""
    return {
        "tether_version": __version__,
        "git_hash": git_hash(),
        "python": platform.python_version(),
        "platform": platform.platform(),
        "cpu_count": os.cpu_count(),
    }


def machine() -> dict[str, Any]:
    """The machine a measurement ran on (recorded with benchmark and report results)."""
    cpu = platform.processor()
    try:
        with open("/proc/cpuinfo") as fh:
            cpu = next(
                (line.split(":", 1)[1].strip() for line in fh if line.startswith("model name")),
                cpu,
            )
    except OSError:
        pass
    return {
        "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
        "platform": platform.platform(),
        "cpu": cpu,
        "cpu_count": os.cpu_count(),
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
    }
