"""The three ``connectivity`` built-ins with the guard only watching: exact and estimated lambda2.

For ``connectivity_empty``, ``connectivity_town`` and ``connectivity_office`` and each
eigensolver setting (the exact solver; the decentralized estimator with 20, 100 and 300
message rounds per sub-step, the built-in's own message faults kept), every seed runs
with ``guard: detect``: nothing is vetoed, every sub-step outside the safe set is
counted. Prints a Markdown table (the one in docs/explanation/continuous.md) and writes
``benchmarks/results/connectivity_guard.json``.

    python benchmarks/connectivity_guard.py                 # 5 seeds each
    python benchmarks/connectivity_guard.py --seeds 2 --rounds 100
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

from tether.config import load_scenario
from tether.runfolder import machine
from tether.runner import build
from tether.sim import simulate

ROOT = Path(__file__).resolve().parents[1]
SCENARIOS = ("connectivity_empty", "connectivity_town", "connectivity_office")
KEYS = ("controller_success", "safe_set_exits", "substeps", "rejected_substeps",
        "min_lambda2_weighted", "min_robot_distance_m", "min_obstacle_clearance_m",
        "max_speed_mps", "max_accel_mps2", "energy_added_j", "energy_net_j",
        "estimator_lambda2_rel_error_mean")  # fmt: skip


def trial(name: str, rounds: int | None, seed: int) -> dict:
    sc = load_scenario(name)
    p = sc.strategy.params
    p["guard"] = "detect"
    if rounds is None:
        p["eigensolver"] = "exact"
    else:
        p["eigensolver"] = "estimator"
        p.setdefault("estimator", {})["rounds_per_substep"] = rounds
    b = build(sc, seed)
    cpu = time.process_time()
    res = simulate(b.world, b.sensor, b.strategy, b.initial, dt_s=sc.sim.dt_s,
                   max_steps=sc.sim.max_steps, rng=b.rng,
                   collision_distance_m=sc.sim.collision_distance_m)  # fmt: skip
    m = res.strategy_metrics
    return {
        "scenario": name,
        "rounds": rounds,
        "seed": seed,
        "cpu_s": time.process_time() - cpu,
        "steps": res.steps,
        **{k: m.get(k) for k in KEYS},
    }


def table(rows: list[dict]) -> str:
    out = ["| scenario | lambda2 | successes | trials with exits | min lambda2 | top speed [m/s] | "
           "top acceleration [m/s^2] | CPU per trial [s] |",
           "| --- | --- | --- | --- | --- | --- | --- | --- |"]  # fmt: skip
    groups: dict[tuple, list[dict]] = {}
    for r in rows:
        groups.setdefault((r["scenario"], r["rounds"]), []).append(r)
    for (name, rounds), rs in groups.items():
        solver = "exact" if rounds is None else f"estimator, {rounds} rounds"
        ok = sum(r["controller_success"] is True for r in rs)
        exits = sum((r["safe_set_exits"] or 0) > 0 for r in rs)
        low = min(r["min_lambda2_weighted"] or 0.0 for r in rs)
        speed = max(r["max_speed_mps"] or 0.0 for r in rs)
        accel = max(r["max_accel_mps2"] or 0.0 for r in rs)
        cpu = sum(r["cpu_s"] for r in rs) / len(rs)
        out.append(f"| `{name}` | {solver} | {ok} / {len(rs)} | {exits} | {low:.3g} | "
                   f"{speed:.2f} | {accel:.3g} | {cpu:.1f} |")  # fmt: skip
    return "\n".join(out)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=5)
    ap.add_argument("--rounds", type=int, nargs="*", default=[20, 100, 300])
    ap.add_argument(
        "--out", type=Path, default=ROOT / "benchmarks" / "results" / "connectivity_guard.json"
    )
    a = ap.parse_args()
    rows = []
    for name in SCENARIOS:
        for rounds in (None, *a.rounds):
            for seed in range(a.seeds):
                rows.append(trial(name, rounds, seed))
                print(json.dumps(rows[-1]), flush=True)
    md = table(rows)
    print(md)
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.out.write_text(json.dumps({"machine": machine(), "rows": rows, "markdown": md}, indent=1)
                     + "\n")  # fmt: skip
    print(f"wrote {a.out}")


if __name__ == "__main__":
    main()
