"""`tether report --paper recurrent`: the recurrent paper's figures and tables from sweeps."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from _cli import one_error_line, tether
from tether.recurrent.report import index_runs
from tether.recurrent.report_settings import setting_label
from tether.recurrent.report_tables import ci95, welch

PAPER = Path(__file__).resolve().parents[1] / "src" / "tether" / "scenarios" / "paper"


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


def test_setting_labels() -> None:
    assert setting_label("fig4", {"method": "ilp", "count_planning_time": True}) == "ilp_t12_timed"
    assert setting_label("fig4", {"method": "apx", "count_planning_time": False}) == (
        "apx_t12_instant"
    )
    assert setting_label("fig5_6", {"theta": 3}) == "theta3"
    assert setting_label("utility", {"coordination": "none"}) == "utility_none"
    assert setting_label("relay", {"relay_binding": "frontiers"}) == "theta1_frontiers"
    with pytest.raises(ValueError, match="unknown campaign kind"):
        setting_label("fig7", {})


def _tiny_campaigns(tmp_path: Path, capsys) -> list[Path]:
    """The four recurrent campaigns on a tiny map (2 robots, 12 steps, 2 seeds), swept."""
    from PIL import Image

    img = np.full((80, 100, 3), 255, np.uint8)  # white free, black walls
    img[[0, -1], :] = img[:, [0, -1]] = 0
    img[40, 10:70] = 0
    Image.fromarray(img).save(tmp_path / "tiny.png")
    folders = []
    for name in ("recurrent_fig4", "recurrent_fig5_6", "recurrent_fig5_6_utility",
                 "recurrent_relay_binding"):  # fmt: skip
        data = yaml.safe_load((PAPER / f"{name}.yaml").read_text())
        axes = data["sweep"]["axes"]
        axes.pop("world.params.stand_in_path")
        data["world"]["params"].pop("stand_in_path")
        axes["world.params.path"] = [str(tmp_path / "tiny.png")]
        if "strategy.params.theta" in axes:
            axes["strategy.params.theta"] = [1, 12]
        data["sweep"] = {"axes": axes, "seeds": 2}
        data["team"]["n_robots"], data["sim"]["max_steps"] = 2, 12
        (tmp_path / f"{name}.yaml").write_text(yaml.safe_dump(data))
        folders.append(tmp_path / name)
        code, _, err = tether(capsys, "sweep", str(tmp_path / f"{name}.yaml"), "--out",
                              str(folders[-1]), "--executor", "serial")  # fmt: skip
        assert code == 0, err
    return folders


def test_paper_report_from_the_campaigns_sweeps(tmp_path: Path, capsys) -> None:
    folders = _tiny_campaigns(tmp_path, capsys)
    code, out, err = tether(capsys, "report", *map(str, folders), "--paper", "recurrent",
                            "--out", str(tmp_path / "paper"))  # fmt: skip
    assert code == 0, err
    index, kinds = index_runs(folders)
    assert set(kinds) == {"fig4", "fig5_6", "utility", "relay"}
    assert set(index.maps) == {"tiny"}
    expect = {
        "apx_t12_timed",
        "ilp_t12_timed",
        "apx_t12_instant",
        "ilp_t12_instant",
        "theta1",
        "theta12",
        "utility_greedy",
        "utility_none",
        "theta1_assigned",
        "theta1_frontiers",
    }
    assert set(index.settings()) == expect
    assert all(len(index.of("tiny", s)) == 2 for s in expect)  # two seeds each

    def summaries(setting: str) -> list[dict]:
        return [json.loads((r / "summary.json").read_text()) for r in index.of("tiny", setting)]

    def same(a: str, b: str) -> bool:
        keep = ("final_explored_fraction", "out_of_comm_mean_steps", "plans", "base_m")
        return [{k: s[k] for k in keep} for s in summaries(a)] == [
            {k: s[k] for k in keep} for s in summaries(b)
        ]

    # one scenario in two campaigns gives the same runs; another setting does not
    assert same("apx_t12_instant", "theta12") and same("theta1", "theta1_assigned")
    assert not same("theta1", "theta12") or not same("utility_greedy", "utility_none")
    table = (tmp_path / "paper" / "recurrent_paper.md").read_text()
    assert "### theta = 1 against Utility" in table and "### Relay binding" in table
    assert "explored at 4 / 8 / 12 steps [%]" in table  # the runs' own length
    fin = [100 * s["final_explored_fraction"] for s in summaries("theta1")]
    mu, half = ci95(fin)
    cell = f"{mu:.1f}" if half is None else f"{mu:.1f} [{mu - half:.1f}, {mu + half:.1f}]"
    assert f"| tiny | θ = 1 | **{cell}** |" in table
    assert "| tiny | θ = 1 − Utility (none) |" in table
    assert "sum to 1 on every one of the 20 runs" in table  # 10 settings x 2 runs
    assert "| all maps | paired by BS position (2 pairs) |" in table
    plans = [s["plans"] for s in summaries("theta1")]
    assert f"| {min(plans)}-{max(plans)} / " in table
    numbers = json.loads((tmp_path / "paper" / "recurrent_paper.json").read_text())
    assert numbers["maps"]["tiny"]["theta12"]["final_explored"] == [
        s["final_explored_fraction"] for s in summaries("theta12")
    ]
    for fig in ("recurrent_fig4_tiny", "recurrent_fig5", "recurrent_fig6", "recurrent_fig_time"):
        assert (tmp_path / "paper" / "figures" / f"{fig}.png").exists()
        assert f"(figures/{fig}.png)" in table
    # a link at a figure's path is never written through: one line, the linked file intact
    mine = tmp_path / "mine.png"
    mine.write_bytes(b"the user's own file")
    link = tmp_path / "paper" / "figures" / "recurrent_fig5.png"
    link.unlink()
    link.symlink_to(mine)
    code, out, err = tether(capsys, "report", *map(str, folders), "--paper", "recurrent",
                            "--out", str(tmp_path / "paper"))  # fmt: skip
    one_error_line(code, err, "recurrent_fig5.png: is a symbolic link")
    assert mine.read_bytes() == b"the user's own file" and link.is_symlink()
    # a report of the user's own in the folder is never replaced
    theirs = tmp_path / "notes"
    theirs.mkdir()
    (theirs / "recurrent_paper.md").write_text("# My notes on the paper\n")
    code, out, err = tether(capsys, "report", *map(str, folders), "--paper", "recurrent",
                            "--out", str(theirs))  # fmt: skip
    one_error_line(code, err, "tether did not write")
    assert (theirs / "recurrent_paper.md").read_text() == "# My notes on the paper\n"
    assert not (theirs / "figures").exists()


def test_paper_report_refuses_what_it_cannot_use(tmp_path: Path, capsys) -> None:
    code, _, err = tether(capsys, "report", str(tmp_path), "--paper", "recurrent")
    assert code == 2 and "not a finished sweep folder" in err
    code, _, err = tether(capsys, "report", str(tmp_path), "--paper", "silent")
    assert code == 2 and "--paper silent: unknown paper; expected one of: recurrent" in err
    code, _, err = tether(capsys, "report", str(tmp_path), str(tmp_path))
    assert code == 2 and "give one sweep folder" in err
    sweep = tmp_path / "s.yaml"
    sweep.write_text(
        "team: {n_robots: 2}\nsensing: {range_m: 5}\nsim: {max_steps: 3}\n"
        "strategy: {name: silent, params: {trajectory: {kind: waypoints, "
        "waypoints: [[0, 0], [1, 0]]}}}\nsweep: {strategy.params.d0_m: [2.0, 3.0]}\n"
    )
    code, _, err = tether(capsys, "sweep", str(sweep), "--out", str(tmp_path / "sw"),
                          "--executor", "serial")  # fmt: skip
    assert code == 0, err
    code, _, err = tether(capsys, "report", str(tmp_path / "sw"), "--paper", "recurrent")
    assert code == 2 and "not a sweep of one of the recurrent paper's campaigns" in err


def test_the_module_is_not_a_second_report_command() -> None:
    done = subprocess.run([sys.executable, "-m", "tether.recurrent.report", "out"],
                          capture_output=True, text=True, timeout=120)  # fmt: skip
    assert done.returncode == 2 and "tether report SWEEP_DIR ... --paper recurrent" in done.stderr
