"""Steps per second of ``silent`` for 20, 1,000 and 10,000 robots.

One step = sensing (k-d tree neighbour search, occlusion by robot bodies, noise) + the
Local Steering Strategy of every robot + the team's metrics (components; lambda2 up to
500 robots), at constant density (a jittered 7 m lattice, range 15 m: about 6-7
neighbours per robot). The compiled kernels run (numba loaded before anything is
timed), and the first steps of every size, which compile or load them, are timed
apart as the warm-up: no compilation is ever inside a steady-state number.
"""

from __future__ import annotations

import numpy as np

from suite.core import Line, cpu_clock, row
from suite.report import num, register_table

SIZES = (20, 1_000, 10_000)


def lattice_team(n: int, spacing_m: float, rng: np.random.Generator) -> np.ndarray:
    side = int(np.ceil(np.sqrt(n)))
    grid = np.stack(np.meshgrid(np.arange(side), np.arange(side), indexing="ij"), -1)
    pts = grid.reshape(-1, 2)[:n] * spacing_m
    return pts + rng.uniform(-0.25, 0.25, pts.shape) * spacing_m


def steps(n: int, count: int, warmup: int = 2) -> dict:
    """CPU seconds of ``warmup`` first steps, then of ``count`` steps by part."""
    from tether.paths.trajectory import Polyline
    from tether.sensing import SensorModel, sense
    from tether.silent.strategy import SilentStrategy
    from tether.sim import StepContext, TeamState, team_metrics
    from tether.world.world import World

    rng = np.random.default_rng(0)
    world = World(dim=2)
    pos = lattice_team(n, 7.0, rng)
    err = np.radians(12)
    sensor = SensorModel(
        15.0, body_radius_m=0.5, radial_error_m=0.45, angular_error_rad=err, noise="uniform"
    )
    path = Polyline(np.array([pos[0], pos[0] + [1000.0, 0.0]]))
    strategy = SilentStrategy(
        d_max_m=15.0,
        trajectory=path,
        leader=0,
        d0_m=8.0,
        radial_error_m=0.45,
        angular_error_rad=err,
    )
    state = TeamState.at_rest(pos)
    strategy.reset(world, state, rng)
    parts = np.zeros(3)
    links = 0
    warm = 0.0
    for k in range(warmup + count):
        t0 = cpu_clock()
        obs = sense(state.positions, sensor, rng, world)
        t1 = cpu_clock()
        state = strategy.step(StepContext(k, float(k), 1.0, world, state, obs, rng))
        t2 = cpu_clock()
        rec = team_metrics(k, float(k), state.positions, obs, 1.0)
        t3 = cpu_clock()
        if k < warmup:
            warm += t3 - t0
            continue
        parts += (t1 - t0, t2 - t1, t3 - t2)
        links += rec.n_links
    per = parts / count
    return {
        "robots": n,
        "steps": count,
        "warmup_s": warm,
        "step_s": float(per.sum()),
        "sense_s": float(per[0]),
        "strategy_s": float(per[1]),
        "metrics_s": float(per[2]),
        "mean_links": links / count,
    }


@row("silent_step", "silent: sensing + steering + metrics per step, 20 to 10,000 robots")
def silent_step(quick: bool) -> dict:
    import numba  # noqa: F401  (loaded first: the shared paths then run their kernels)

    from tether import jit

    details, lines = [], []
    with jit.using(True):
        for n in SIZES[:2] if quick else SIZES:
            count = {20: 2000, 1_000: 60, 10_000: 10}[n] // (10 if quick else 1)
            rec = steps(n, count)
            details.append(rec)
            if n == 20:
                line = Line("silent step, 20 robots", "ms", 1e3 * rec["step_s"])
                line.goal, line.goal_value = "<= 0.2 ms", 0.2
            elif n == 10_000:
                label = "silent steps per second, 10,000 robots, occlusion on"
                line = Line(label, "/s", 1.0 / rec["step_s"], higher_is_better=True)
                line.goal, line.goal_value = ">= 10 /s", 10.0
            else:
                line = Line(f"silent step, {n:,} robots", "ms", 1e3 * rec["step_s"])
            line.warmup_s = rec["warmup_s"]
            lines.append(line)
    if len(details) == 3:
        details.append({"ratio_10000_over_1000": details[2]["step_s"] / details[1]["step_s"]})
    return {"lines": lines, "details": {"sizes": details}}


@register_table("silent")
def table_silent(doc: dict) -> str:
    out = [
        "| robots | steps/s | ms per step | sensing / steering / metrics (ms) | links | "
        "first 2 steps (s) |",
        "| ---: | ---: | ---: | --- | ---: | ---: |",
    ]
    for r in doc["rows"].get("silent_step", {}).get("details", {}).get("sizes", []):
        if "robots" not in r:
            continue
        out.append(
            f"| {r['robots']:,} | {num(1 / r['step_s'])} | {num(1e3 * r['step_s'])} | "
            f"{num(1e3 * r['sense_s'])} / {num(1e3 * r['strategy_s'])} / "
            f"{num(1e3 * r['metrics_s'])} | {num(r['mean_links'])} | {num(r['warmup_s'])} |"
        )
    return "\n".join(out)
