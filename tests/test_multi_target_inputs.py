"""Bad ``multi_target`` inputs end in one line and exit code 2, from ``validate`` as from ``run``.

The probe's cases: a planning cell (``strategy.params.r_grid_m``) whose grid would not
fit in memory (it is built at reset, after ``build``, so the check must be in
``build``), unchecked ``height_m`` ranges of the targets and of the start, multi-line
pydantic dumps of the target generator's parameters, and unbounded target counts.
"""

from __future__ import annotations

import tracemalloc
from pathlib import Path

import pytest

from _cli import tether
from tether.continuous.exploration.checks import planning_bytes
from tether.continuous.exploration.targets import MAX_TARGETS, PaperRandomParams
from tether.paths.astar import planning_grid
from tether.runner import build


def one_line(code: int, err: str, *needles: str) -> str:
    assert code == 2, err
    assert "Traceback" not in err and "internal error" not in err, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    for needle in needles:
        assert needle in lines[0], f"{needle!r} not in {lines[0]!r}"
    return lines[0]


def sets(*pairs: str) -> list[str]:
    return [a for p in pairs for a in ("--set", p)]


# --------------------------------------------------------------------------- r_grid_m


@pytest.mark.parametrize("r_grid", ["0.01", "0.05", "1e-300"])
def test_a_too_fine_planning_grid_is_refused_by_validate_and_run(capsys, tmp_path, r_grid):
    args = sets(f"strategy.params.r_grid_m={r_grid}", "sim.max_steps=3")
    code, _, err = tether(capsys, "validate", "multi_target_empty", *args)
    line = one_line(code, err, "multi_target_empty: strategy.params.r_grid_m:", "50 x 70 x 10 m")
    assert "raise strategy.params.r_grid_m to at least" in line
    out = tmp_path / "run"
    code, _, err = tether(capsys, "run", "multi_target_empty", *args, "--no-figures",
                          "--out", str(out))  # fmt: skip
    assert one_line(code, err) == line  # run refuses with the same line, before simulating
    assert not out.exists()


def test_a_coarse_world_grid_names_its_size(capsys):
    # 1000 m world cells round the town's grid up to 1000 m a side: 2.4e9 planning cells
    code, _, err = tether(capsys, "validate", "multi_target_town",
                          *sets("world.params.resolution_m=1000"))  # fmt: skip
    one_line(code, err, "strategy.params.r_grid_m", "1000 x 1000 x 1000 m")


def test_the_suggested_cell_fits_and_the_refusal_follows_the_allowance(capsys, monkeypatch):
    # the default empty space (88,172 cells of 0.75 m) needs ~17 MB: refused under 10 MiB
    monkeypatch.setenv("TETHER_MEMORY_LIMIT_GB", str(10 / 1024))
    base = sets("sim.max_steps=3")
    code, _, err = tether(capsys, "validate", "multi_target_empty", *base)
    line = one_line(code, err, "strategy.params.r_grid_m: planning cells of 0.75 m",
                    "more than the 10.0 MiB allowed here")  # fmt: skip
    suggested = line.split("at least ")[1].split(" m")[0]
    assert float(suggested) > 0.75
    code, out, err = tether(capsys, "validate", "multi_target_empty",
                            *base, *sets(f"strategy.params.r_grid_m={suggested}"))  # fmt: skip
    assert code == 0, err


@pytest.mark.parametrize("cell_m", [0.75, 0.5])
def test_the_planning_estimate_counts_the_cells_and_bounds_the_memory(cell_m):
    world = build("multi_target_office").world
    cells, need = planning_bytes(world.grid.size_m, cell_m)
    tracemalloc.start()
    plan = planning_grid(world, cell_m=cell_m, inflate_m=0.5)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert cells == plan.occupied.size
    assert peak <= need  # the estimate is not below what building the grid takes


def test_the_default_scenarios_still_validate(capsys):
    for name in ("multi_target_empty", "multi_target_office"):
        code, out, err = tether(capsys, "validate", name)
        assert code == 0, err


# --------------------------------------------------------------------------- heights


@pytest.mark.parametrize(
    ("value", "needle"),
    [("[5]", "need two heights"), ("[]", "need two heights"), ("[8,2]", "low <= high"),
     ("[100,200]", "outside the world's heights [0, 10] m")],
)  # fmt: skip
def test_target_heights_are_checked(capsys, value, needle):
    code, _, err = tether(capsys, "validate", "multi_target_empty",
                          *sets(f"strategy.params.targets.params.height_m={value}"))  # fmt: skip
    one_line(code, err, "strategy.params.targets.params.height_m:", needle)


@pytest.mark.parametrize(
    ("value", "needle"),
    [("[1,2,3]", "need two heights"), ("[5]", "need two heights"), ("[]", "need two heights"),
     ("[8,2]", "low <= high"), ("[20,30]", "outside the world's heights")],
)  # fmt: skip
def test_start_heights_are_checked(capsys, value, needle):
    code, _, err = tether(capsys, "validate", "multi_target_empty",
                          *sets("strategy.params.start.center_m=null",
                                f"strategy.params.start.height_m={value}"))  # fmt: skip
    one_line(code, err, "strategy.params.start.height_m:", needle)


def test_a_start_height_range_inside_the_world_places_the_team(capsys):
    code, _, err = tether(capsys, "validate", "multi_target_empty",
                          *sets("strategy.params.start.center_m=null",
                                "strategy.params.start.height_m=[3,6]"))  # fmt: skip
    assert code == 0, err


# --------------------------------------------------------------------------- generator params


@pytest.mark.parametrize(
    ("setting", "field"),
    [("bogus=1", "params.bogus: unknown key"), ("explorers=abc", "params.explorers:"),
     ("queues=[{robot: 1, targets: []}]", "params.queues: unknown key"),
     ("explorers=[-1]", "params.explorers.0:"),
     ("explorers=[100000000]", "params.explorers: 100,000,000 targets in all")],
)  # fmt: skip
def test_generator_params_fail_on_one_line_with_their_path(capsys, setting, field):
    code, _, err = tether(capsys, "validate", "multi_target_empty",
                          *sets(f"strategy.params.targets.params.{setting}"))  # fmt: skip
    one_line(code, err, f"multi_target_empty: strategy.params.targets.{field}")


def test_fixed_queues_errors_name_the_queue(capsys):
    code, _, err = tether(capsys, "validate", "multi_target_empty",
                          *sets("strategy.params.targets.kind=fixed",
                                "strategy.params.targets.params={queues: "
                                "[{robot: 1, targets: []}]}"))  # fmt: skip
    one_line(code, err, "strategy.params.targets.params.queues.0.targets:", "non-empty")


def test_the_target_cap_is_inclusive():
    assert sum(PaperRandomParams(explorers=[MAX_TARGETS]).explorers) == MAX_TARGETS
    with pytest.raises(ValueError, match="more than the 100,000 allowed"):
        PaperRandomParams(explorers=[MAX_TARGETS // 2, MAX_TARGETS // 2 + 1])


def test_no_run_folder_is_left_by_a_refused_target_count(capsys, tmp_path: Path):
    out = tmp_path / "run"
    bad = [*sets("strategy.params.targets.params.explorers=[100000000]"), "--out", str(out)]
    code, _, err = tether(capsys, "run", "multi_target_empty", "--no-figures", *bad)
    one_line(code, err, "explorers")
    assert not out.exists()


def test_a_planning_grid_beyond_max_cells_is_refused_within_the_allowance(capsys, monkeypatch):
    # 0.02 m in the 10 x 15 x 3 m office: 5.6e7 cells (~10.5 GiB, under a 100 GiB allowance)
    monkeypatch.setenv("TETHER_MEMORY_LIMIT_GB", "100")
    code, _, err = tether(capsys, "validate", "multi_target_office",
                          *sets("strategy.params.r_grid_m=0.02"))  # fmt: skip
    one_line(code, err, "strategy.params.r_grid_m", "more than the 50,000,000 a grid may have")


# --------------------------------------------------------------------------- connectivity's keys


def test_connectivity_s_external_force_is_refused_not_ignored(capsys):
    """multi_target's ``f_i`` is Algorithm 2's traveling force: an ``external`` block
    (the ``connectivity`` strategy's stand-in for it) would change nothing."""
    code, _, err = tether(capsys, "validate", "multi_target_experiment",
                          *sets("strategy.params.external.kind=random"))  # fmt: skip
    one_line(code, err, "multi_target_experiment: strategy.params.external")
    code, _, err = tether(capsys, "validate", "connectivity_town",
                          *sets("strategy.params.external.kind=random"))  # fmt: skip
    assert code == 0, err


def test_a_failed_robot_must_be_in_the_team(capsys):
    args = sets(
        "strategy.params.eigensolver=estimator", "strategy.params.estimator.failures={9: 3}"
    )
    code, _, err = tether(capsys, "validate", "multi_target_experiment", *args)
    one_line(code, err, "strategy.params.estimator.failures: 9 is not a robot index in 0..5")
