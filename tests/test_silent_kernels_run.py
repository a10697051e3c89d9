"""A whole ``silent_demo`` run with the compiled kernels on and off.

Sensing (occlusion, noise), the desired steps and the metrics are bit-identical
between the kernels and the numpy reference; the constrained steps agree to rounding
(``acos``/``cos`` from the C library); the recorded positions, metrics and links of
the whole run are identical (lambda2 included: the compiled metrics call LAPACK's
``dsyevd`` as ``numpy.linalg.eigh`` does).
"""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np
import pyarrow.parquet as pq
import pytest

from tether import jit
from tether.config import load_scenario
from tether.runner import run

pytest.importorskip("numba")


def test_silent_demo_same_run_with_and_without_kernels(tmp_path) -> None:  # noqa: ANN001
    scenario = load_scenario("silent_demo")
    tables = {}
    for on in (False, True):
        with jit.using(on):
            out = run(scenario, out_dir=tmp_path / str(on), seed=2, figures=False)
        tables[on] = {
            name: pq.read_table(out.path / name).to_pydict()
            for name in ("robots.parquet", "steps.parquet", "links.parquet")
        }
    robots = tables[False]["robots.parquet"]
    assert len(robots["x_m"]) > 100
    for name, ref in tables[False].items():
        fast = tables[True][name]
        assert fast.keys() == ref.keys(), name
        for key in ref:  # positions and metrics identical, bit for bit
            np.testing.assert_array_equal(np.asarray(fast[key]), np.asarray(ref[key]), key)


def test_a_small_silent_run_does_not_load_numba(tmp_path) -> None:  # noqa: ANN001
    """Small teams use the kernels only once numba is loaded (or ``TETHER_JIT=on``):
    with the kernels enabled but numba not imported, ``silent_demo`` (sensing,
    strategy, metrics) runs the reference paths and never pays numba's start-up."""
    code = (
        "import sys\n"
        "from tether import jit\n"
        "jit.set_enabled(True)\n"
        "from tether.runner import run\n"
        "run('silent_demo', out_dir=sys.argv[1], seed=0, figures=False)\n"
        "print('numba' in sys.modules)\n"
    )
    env = dict(os.environ, TETHER_JIT="auto")
    out = subprocess.run([sys.executable, "-c", code, str(tmp_path / "run")], env=env,
                         capture_output=True, text=True, check=True)  # fmt: skip
    assert out.stdout.strip().splitlines()[-1] == "False"
