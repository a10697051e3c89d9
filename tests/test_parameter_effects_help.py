"""A stalled prime in ``multi_target``: the watchdog (``stall_timeout_s``) and the helpers
it recruits (``help_*``; ``docs/multi_target.md``, "A stalled prime recruits helpers").

The stall is real: robot 0 anchors at its start for 60 s with the paper's unbounded
anchor force, robot 3 (prime) heads for a target 40 m ahead, and the row of four robots
can stretch to about 16 m (links below ``Rs`` = 6 m): the prime stops at x = 16.3 m,
after about 6 s of travel. Helpers (robots 1 and 2, one and two hops from it) move up
to it and let it gain another metre.
"""

from __future__ import annotations

from functools import cache
from typing import Any

import numpy as np

from _continuous_runs import FAR_TARGET, run, scenario
from _parameters import effect

NO_WATCHDOG = {"max_anchor_force_n": None, "stall_timeout_s": None}


def held(steps: int = 140, **params: Any):  # noqa: ANN201
    """The held row (module docstring), help asked after 2 s unless ``params`` say else
    (runs are deterministic: each setting runs once per session)."""
    return _held(steps, tuple(sorted(params.items())))


@cache
def _held(steps: int, items: tuple[tuple[str, Any], ...]):  # noqa: ANN202
    params = dict(items)
    data = scenario("multi_target", **{**NO_WATCHDOG, "help_after_s": 2.0, **params})
    data["strategy"]["params"]["targets"]["params"]["queues"] = [
        {"robot": 0, "targets": [[0.0, 0.0, 5.0]], "stay_s": 60.0},
        {"robot": 3, "targets": [FAR_TARGET], "stay_s": 1.0},
    ]
    return run(data, steps)


def help_events(r) -> list[tuple[str, int, Any]]:  # noqa: ANN001
    """``(kind, step, hops)`` of the help events (all the prime's: robot 3)."""
    return [(e["kind"], e["step"], e.get("hops")) for e in r.recorder.events
            if e["kind"].startswith("help")]  # fmt: skip


def prime_x(r) -> float:  # noqa: ANN001
    return float(r.positions[-1, 3, 0])


@effect("multi_target:stall_timeout_s")
def test_a_prime_stalled_for_stall_timeout_drops_its_target() -> None:
    never = held(140, help_after_s=None)
    assert never.metrics["targets_dropped"] == 0
    assert abs(prime_x(never) - float(never.positions[-40, 3, 0])) < 0.01  # stalled
    for timeout_s in (3.0, 6.0):
        r = held(140, help_after_s=None, stall_timeout_s=timeout_s)
        drop = [e for e in r.recorder.events if e["kind"] == "target_dropped"]
        assert [(e["robot"], e["reason"]) for e in drop] == [(3, "stalled")]
        assert r.metrics["targets_dropped"] == 1
        if timeout_s == 3.0:
            first = drop[0]["step"]
        else:
            assert drop[0]["step"] == first + 30  # 3 s later, at 10 steps per second


@effect("multi_target:help_after_s")
def test_a_prime_stalled_for_help_after_s_asks_for_help_and_gets_farther() -> None:
    alone = held(help_after_s=None)
    helped = held()
    later = held(help_after_s=4.0)
    assert alone.metrics["help_requests"] == 0 and alone.metrics["helper_robot_s"] == 0
    assert helped.metrics["help_requests"] == 1 and helped.metrics["helper_robot_s"] > 5
    first = help_events(helped)[0]
    assert first[0] == "help_requested" and first[2] == 1
    assert help_events(later)[0][1] == first[1] + 20  # 2 s more of stall before asking
    assert prime_x(helped) > prime_x(alone) + 0.5


@effect("multi_target:help_max_hops")
def test_the_request_deepens_by_a_hop_per_help_after_s_up_to_max_hops() -> None:
    deep, shallow = held(), held(help_max_hops=1)
    assert [h for _, _, h in help_events(deep)] == [1, 2, 3]
    assert [h for _, _, h in help_events(shallow)] == [1]
    # robot 1, two hops from the prime, helps only when the request reaches it
    assert deep.metrics["helper_robot_s"] > shallow.metrics["helper_robot_s"] + 2.0


@effect("multi_target:help_until")
def test_help_until_progress_ends_the_request_at_the_prime_s_first_progress() -> None:
    kept = [k for k, _, _ in help_events(held())]
    ended = help_events(held(help_until="progress"))
    assert "help_ended" not in kept  # arrival: the request lasts the prime's turn
    kinds = [k for k, _, _ in ended]
    assert kinds[:3] == ["help_requested", "help_ended", "help_requested"]
    assert ended[2][2] == 1  # a new stall starts again from one hop


@effect("multi_target:help_lambda_factor")
def test_helpers_that_give_up_links_let_the_prime_get_farther() -> None:
    """With ``help_lambda_factor`` 0.1 (the outdoor preset's) a helper's own connectivity
    force is scaled down: it defends its links less, the row stretches further."""
    full = held(help_lambda_factor=None)
    scaled = held(help_lambda_factor=0.1)
    assert prime_x(scaled) > prime_x(full) + 0.2
    stretch = [float(np.diff(r.positions[-1, :, 0]).sum()) for r in (full, scaled)]
    assert stretch[1] > stretch[0]
