"""The report's statistics and the doc tables printed from run folders (issue 13 tables)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from tether.recurrent.report_settings import run_dir
from tether.recurrent.report_tables import ci95, markdown, welch


def test_ci95_and_welch_by_hand() -> None:
    mu, half = ci95([1.0, 2.0, 3.0, 4.0, 5.0])
    # t(0.975, 4) = 2.776445; sd = sqrt(2.5); half = t * sd / sqrt(5)
    assert mu == 3.0 and half == pytest.approx(2.776445 * np.sqrt(2.5) / np.sqrt(5), rel=1e-6)
    assert ci95([None, 2.0]) == (2.0, None) and ci95([]) == (None, None)
    d, half, p = welch([1.0, 2.0, 3.0], [2.0, 4.0, 6.0])
    # means 2 and 4; se^2 = 1/3 + 4/3; dof = se^4 / ((1/3)^2/2 + (4/3)^2/2) = 2.94
    se = np.sqrt(5 / 3)
    dof = se**4 / ((1 / 3) ** 2 / 2 + (4 / 3) ** 2 / 2)
    from scipy.stats import t

    assert d == -2.0 and half == pytest.approx(t.ppf(0.975, dof) * se)
    assert 0.05 < p < 1


def test_theta1_is_the_default_binding_run() -> None:
    assert run_dir(Path("o"), "m", "theta1", 0).parent.name == "theta1_assigned"
    assert run_dir(Path("o"), "m", "utility", 0).parent.name == "utility_greedy"
    assert run_dir(Path("o"), "m", "apx_t12_instant", 0).parent.name == "theta12"
    assert run_dir(Path("o"), "m", "theta3", 2) == Path("o/runs/m/theta3/seed-2")


def test_comparison_tables_from_a_tiny_report(tmp_path: Path) -> None:
    from PIL import Image

    from tether.recurrent.report import make_report

    img = np.full((80, 100, 3), 255, np.uint8)  # white free, black walls
    img[[0, -1], :] = img[:, [0, -1]] = 0
    img[40, 10:70] = 0
    Image.fromarray(img).save(tmp_path / "tiny.png")
    settings = ("theta1", "theta1_frontiers", "utility_greedy", "utility_none")
    rep = make_report(tmp_path / "out", maps=("tiny",), runs=2, steps=12, n_robots=2,
                      thetas=(1,), settings=settings, maps_dir=tmp_path, workers=1)  # fmt: skip
    e = rep["maps"]["tiny"]
    # theta1 (the default binding) ran under its spelled-out label
    assert sorted(p.name for p in (tmp_path / "out" / "runs" / "tiny").iterdir()) == [
        "theta1_assigned", "theta1_frontiers", "utility_greedy", "utility_none"]  # fmt: skip
    for label in settings:
        shares = [e[label][f"time_{k}_frac_mean"] for k in
                  ("moving", "relaying", "waiting", "returning")]  # fmt: skip
        assert sum(shares) == pytest.approx(1.0)
        assert len(e[label]["time_to_50pct_s"]) == 2
    table = markdown(tmp_path / "out")
    assert "### theta = 1 against Utility" in table and "### Relay binding" in table
    runs = sorted((tmp_path / "out" / "runs" / "tiny" / "theta1_assigned").glob("seed-*"))
    fin = [100 * json.loads((r / "summary.json").read_text())["final_explored_fraction"]
           for r in runs]  # fmt: skip
    mu, half = ci95(fin)
    cell = f"{mu:.1f}" if half is None else f"{mu:.1f} [{mu - half:.1f}, {mu + half:.1f}]"
    assert f"| tiny | θ = 1 | **{cell}** |" in table
    assert "| tiny | θ = 1 − Utility (none) |" in table
    assert "sum to 1 on every one of the 8 runs" in table  # 4 settings x 2 runs
    assert "| all maps | paired by BS position (2 pairs) |" in table  # 2 seeds, 1 map
    plans = [json.loads((r / "summary.json").read_text())["plans"] for r in runs]
    assert f"| {min(plans)}-{max(plans)} / " in table  # theta = 1's plans per run, range
    for fig in ("fig5.png", "fig6.png", "fig_time.png"):
        assert (tmp_path / "out" / fig).exists()
