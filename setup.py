"""Build hook: the package records the git commit it was built from (``build_commit.txt``).

Everything else about the package is in ``pyproject.toml``. A run records the commit in
its ``summary.json`` (``provenance.git_hash``); a package built outside a git checkout
(an sdist) has none and runs say ``unknown``.
"""

import subprocess
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

ROOT = Path(__file__).resolve().parent


def _commit() -> str | None:
    try:
        out = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True,
                             text=True, timeout=10)  # fmt: skip
    except (OSError, subprocess.TimeoutExpired):
        return None
    inside = subprocess.run(["git", "ls-files", "--error-unmatch", "pyproject.toml"], cwd=ROOT,
                            capture_output=True, timeout=10)  # fmt: skip
    return out.stdout.strip() or None if out.returncode == inside.returncode == 0 else None


class BuildWithCommit(build_py):
    def run(self) -> None:
        super().run()
        commit = _commit()
        if commit and not self.dry_run:
            target = Path(self.build_lib) / "tether" / "build_commit.txt"
            target.write_text(commit + "\n")


setup(cmdclass={"build_py": BuildWithCommit})
