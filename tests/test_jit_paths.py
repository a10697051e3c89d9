"""Each strategy's hot paths run both ways in the default suite, with the same results.

The suite runs the numpy reference unless a test pins the compiled kernels
(``tests/conftest.py``); whole runs of ``silent``, ``connectivity`` and ``multi_target``
are compared in ``test_silent_kernels_run.py`` and ``test_kernels.py``. Here: the
estimator over the message layer (``connectivity``) and the exploration strategies
(depth sensor, line of sight, geodesics, exploration graph, APX), kernels on and off.
"""

from __future__ import annotations

import numpy as np
import pytest

from _parameter_runs import changed, ran
from tether import jit
from tether.config import load_scenario

pytest.importorskip("numba")

#: metrics that measure the machine, not the run
TIMING = ("timing_s", "planning_time_mean_s", "planning_time_max_s", "planning_time_total_s")


def estimator_run() -> dict:
    data = load_scenario("connectivity_empty").model_dump(mode="json")
    data["strategy"]["params"].update(
        eigensolver="estimator",
        external={"kind": "random", "magnitude_n": 3.0, "hold_s": 1.0},
        estimator={"warmup_rounds": 200, "loss_probability": 0.2, "failures": {2: 400}},
    )
    return changed(data, output__figures=False, sim__max_steps=25)


def exploration_run(name: str) -> dict:
    data = load_scenario("recurrent_demo").model_dump(mode="json")
    data["strategy"]["name"] = name
    if name == "utility":
        data["strategy"]["params"] = {"ratio": 0.5}
    return changed(data, output__figures=False, sim__max_steps=40, team__n_robots=4)


@pytest.mark.parametrize(
    "make", [estimator_run, lambda: exploration_run("recurrent"),
             lambda: exploration_run("utility")],
    ids=["connectivity-estimator", "recurrent", "utility"],
)  # fmt: skip
def test_the_same_run_with_the_kernels_on_and_off(make) -> None:  # noqa: ANN001
    runs = {}
    for on in (False, True):
        with jit.using(on):
            runs[on] = ran(make())
            assert jit.enabled() is on
    ref, fast = runs[False], runs[True]
    np.testing.assert_array_equal(fast.positions, ref.positions)
    assert [r.n_links for r in fast.result.records] == [r.n_links for r in ref.result.records]
    assert [r.connected for r in fast.result.records] == [r.connected for r in ref.result.records]
    np.testing.assert_allclose(
        [r.lambda2 for r in fast.result.records], [r.lambda2 for r in ref.result.records],
        rtol=1e-9, atol=1e-12,
    )  # fmt: skip
    keep = {k: v for k, v in ref.metrics.items() if k not in TIMING}
    assert {k: fast.metrics[k] for k in keep} == keep
    assert np.ptp(ref.positions, axis=0).max() > 0.5  # the run did move


def test_the_suite_pins_the_path_for_itself_and_the_commands_it_starts() -> None:
    """``TETHER_JIT=auto`` would pick a path by the numba cache and the clock."""
    import os

    assert jit.mode() in ("off", "on")
    assert os.environ["TETHER_JIT"].lower() in ("0", "off", "1", "on")
