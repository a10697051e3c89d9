"""The parameters of ``continuous_exploration`` (the mission's continuous paradigm) that the
other explorers do not share change a run the way their documentation says."""

from __future__ import annotations

import numpy as np
import pytest

from _parameters import NO_EFFECT, effect
from test_parameter_effects_exploration import explore
from tether.continuous.connectivity.params import TABLE2
from tether.continuous.exploration.targets import TargetBook
from tether.errors import ScenarioError

NAME = "continuous_exploration"


def run(steps: int, **params: object):  # noqa: ANN201
    return explore(NAME, steps, **params)


@effect(f"{NAME}:preset")
def test_preset_picks_the_table2_column() -> None:
    for preset in ("office", "experiment"):
        controller = run(0, preset=preset).built.strategy.policy.params
        assert controller.rs_m == TABLE2[preset]["rs_m"]
        assert controller.ro_outer_m == TABLE2[preset]["ro_outer_m"]


@effect(f"{NAME}:multi_target")
def test_multi_target_overrides_reach_the_controller() -> None:
    controller = run(0, multi_target={"kp_n_per_m": 1.5}).built.strategy.policy.params
    assert controller.kp_n_per_m == 1.5
    with pytest.raises(ScenarioError, match="strategy.params.multi_target"):
        run(0, multi_target={"no_such_gain": 1.0})


@effect(f"{NAME}:cruise_fraction")
def test_the_cruise_fraction_sets_the_traveling_speed() -> None:
    # the traveling force aims at v_cruise = cruise_fraction x speed_m_s; the
    # distance a team covers in a short run is not a stable oracle (which robot is
    # elected prime and where its frontier lies changes with the last bits of the
    # floating point, so it differs between processors)
    for fraction in (0.3, 0.9):
        controller = run(0, cruise_fraction=fraction, speed_m_s=0.4).built.strategy.policy.params
        assert controller.v_cruise_mps == pytest.approx(fraction * 0.4)


@effect(f"{NAME}:control_period_s")
def test_control_periods_per_step() -> None:
    fine, coarse = (run(3, control_period_s=p).metrics["control_periods"] for p in (0.1, 0.25))
    assert fine * 4 == coarse * 10  # 10 and 4 periods of each 1 s step


@effect(f"{NAME}:coarse_cell_m")
def test_frontiers_are_picked_on_coarse_cells() -> None:
    cells = {}
    for cell_m in (0.3, 1.0):
        r = run(2, coarse_cell_m=cell_m)
        policy = r.built.strategy.policy
        assert policy.picker.coarse_factor == round(cell_m / 0.1)
        cells[cell_m] = policy.target_cell[np.isfinite(policy.target_cell[:, 0])]
    assert len(cells[0.3]) and len(cells[1.0])
    assert not np.array_equal(cells[0.3], cells[1.0])


@effect(f"{NAME}:stay_s")
def test_every_frontier_target_carries_the_stay(monkeypatch: pytest.MonkeyPatch) -> None:
    # Delta t of each target: how long its robot holds it before it may leave (the
    # count of frontiers given in a short run is no stable oracle: it changes with the
    # last bits of the floating point, so between processors)
    stays: list[float] = []
    add = TargetBook.add

    def spy(self: TargetBook, robot: int, position_m: object, stay_s: float = 3.0, **kw: object):  # noqa: ANN202
        stays.append(stay_s)
        return add(self, robot, position_m, stay_s, **kw)

    monkeypatch.setattr(TargetBook, "add", spy)
    for stay in (0.0, 7.5):
        stays.clear()
        run(3, stay_s=stay)
        assert stays and set(stays) == {stay}


@effect(f"{NAME}:target_timeout_s")
def test_a_target_past_its_timeout_expires() -> None:
    dropped = run(20, target_timeout_s=1.0).metrics["targets_dropped_by_reason"]
    assert dropped.get("expired", 0) > 0
    assert run(20).metrics["targets_dropped_by_reason"].get("expired", 0) == 0


NO_EFFECT[f"{NAME}:scan_steps"] = (
    "refused unless 1: the controller moves its robots itself, so a scan never holds one "
    "(test_scan_steps_are_refused)"
)


def test_scan_steps_are_refused() -> None:
    with pytest.raises(ScenarioError, match="scan_steps"):
        run(1, scan_steps=8)
