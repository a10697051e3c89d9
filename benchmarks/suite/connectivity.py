"""One evaluation of ``connectivity``'s force: weights, eigenpair, gradient.

Every integrator sub-step evaluates ``compute_weights`` + the Fiedler pair (or the
decentralized estimator's rounds) + the connectivity force (the robots' update itself is
a few microseconds and is not included), on a team in free
3-D space (200 m x 200 m x 10 m) or in the town scene (50 m x 70 m, 0.25 m). Teams up
to 1,000 robots are placed by ``safe_team``; 10,000 robots on a jittered 3 m lattice.
The team is at rest (every call the same configuration), so the warm solver keeps its
factorization as it does between the sub-steps of a slow team; ``eigen_fresh`` is the
solve with a new factorization (a team that moved more than its spectral gap allows).
Each part is timed in batches after a warm-up call (CPU time).
"""

from __future__ import annotations

import numpy as np

from suite.core import Line, batch, cpu_clock, row
from suite.report import num, register_table

#: the table rows: (world, robots, solver); the goals of the summary lines
CASES = (
    ("free", 10, "exact"),
    ("free", 35, "exact"),
    ("free", 35, "estimator"),
    ("free", 100, "exact"),
    ("free", 1000, "exact"),
    ("free", 10_000, "exact"),
    ("town", 10, "exact"),
    ("town", 35, "exact"),
    ("town", 100, "exact"),
)
GOALS_US = {("free", 35): 50.0, ("town", 35): 100.0, ("free", 1000): 5e3, ("free", 10_000): 1e5}


def world(name: str):  # noqa: ANN201
    from tether.world.scenes import make_scene
    from tether.world.world import World

    if name == "free":
        return World(dim=3, bounds_m=np.array([[0.0, 0, 0], [200.0, 200.0, 10.0]]), name="free")
    w = make_scene("town", 0, size_m=(50.0, 70.0), resolution_m=0.25)
    w.name = name
    return w


def team(w, n: int, params) -> np.ndarray:  # noqa: ANN001
    from tether.continuous.connectivity.placement import safe_team

    rng = np.random.default_rng(n)
    if n >= 10_000:  # 66 x 51 x 3 lattice, 3 m apart (inside R's, outside R'c), jittered
        cells = np.argwhere(np.ones((66, 51, 3), dtype=bool))[:n]
        return w.bounds_m[0] + [1.5, 1.5, 1.0] + 3.0 * cells + rng.uniform(-0.4, 0.4, (n, 3))
    return safe_team(w, n, params, rng, margin_m=5.0, height_m=(1.0, 8.0))


def substep(w, n: int, solver: str, calls: int) -> dict:  # noqa: ANN001
    """Seconds per call of each part and of the whole sub-step; the first call apart."""
    from tether.continuous.connectivity.estimation import FiedlerEstimator
    from tether.continuous.connectivity.gradient import connectivity_force, exact_force, messages
    from tether.continuous.connectivity.strategy import ConnectivityStrategyParams
    from tether.continuous.connectivity.weights import compute_weights
    from tether.graph import WarmState
    from tether.world.clearance import ObstacleIndex

    c = ConnectivityStrategyParams().connectivity()
    q = team(w, n, c)
    obs = ObstacleIndex.from_world(w)
    t0 = cpu_clock()
    graph = compute_weights(q, c, obs)
    lam, nu = graph.fiedler()
    first = cpu_clock() - t0
    est = None
    if solver == "estimator":
        est = FiedlerEstimator.create(n, np.random.default_rng(0))
        est.update(graph, 200)
    state, step_state = WarmState(), WarmState()
    for _ in range(2):  # the factoring path, then the reusing one
        graph.fiedler(guess=nu, state=state)

    def step() -> np.ndarray:
        g = compute_weights(q, c, obs, guess=nu if est is None else None, with_force=est is None)
        if est is None:
            l2, vec = g.fiedler(guess=nu, state=step_state)
            return exact_force(g, l2, vec, c)
        est.update(g, 20)
        l2, vec = est.lambda2, est.vector
        return connectivity_force(g, l2, messages(g, vec), c)

    parts = {
        "weights": lambda: compute_weights(q, c, obs),
        "eigen": (lambda: graph.fiedler(guess=nu, state=state))
        if est is None
        else (lambda: est.update(graph, 20)),
        "gradient": lambda: connectivity_force(graph, lam, messages(graph, nu), c),
        "step": step,
    }
    if est is None:
        parts["eigen_fresh"] = lambda: graph.fiedler(guess=nu)
    out = {"world": w.name, "robots": n, "solver": solver, "links": int(len(graph.pairs))}
    out["first_s"] = first
    for name, fn in parts.items():
        fn()
        out[f"{name}_s"] = min(batch(fn, calls) for _ in range(3))
    return out


@row("connectivity_step", "connectivity: one force evaluation, 10 to 10,000 robots")
def connectivity_step(quick: bool) -> dict:
    from tether import jit

    worlds = {"free": world("free"), "town": world("town")}
    cases = [("free", 35, "exact")] if quick else CASES
    details, lines = [], []
    with jit.using(True):
        for wname, n, solver in cases:
            calls = 3 if n >= 10_000 else 10 if n >= 1000 else (20 if quick else 400)
            rec = substep(worlds[wname], n, solver, calls)
            details.append(rec)
            goal = GOALS_US.get((wname, n)) if solver == "exact" else None
            if goal is None:
                continue
            unit, scale = ("ms", 1e3) if goal >= 1e3 else ("us", 1e6)
            shown = goal / 1e6 * scale
            lines.append(
                Line(
                    f"connectivity force evaluation, {n:,} robots, "
                    + ("free 3-D" if wname == "free" else "town"),
                    unit,
                    rec["step_s"] * scale,
                    goal=f"<= {shown:g} {unit}",
                    goal_value=shown,
                    warmup_s=rec["first_s"],
                )
            )
    return {"lines": lines, "details": {"substeps": details}}


@register_table("connectivity")
def table_connectivity(doc: dict) -> str:
    """The parts of an evaluation in microseconds, per scene, team and solver."""
    out = [
        "| scene | robots | links | solver | weights | eigenpair / estimator | "
        "eigenpair, new factorization | gradient | evaluation |",
        "| --- | ---: | ---: | --- | ---: | ---: | ---: | ---: | ---: |",
    ]
    subs = doc["rows"].get("connectivity_step", {}).get("details", {}).get("substeps", [])
    for r in subs:
        fresh = num(1e6 * r["eigen_fresh_s"]) if "eigen_fresh_s" in r else "-"
        out.append(
            f"| {r['world']} | {r['robots']:,} | {r['links']:,} | {r['solver']} | "
            f"{num(1e6 * r['weights_s'])} | {num(1e6 * r['eigen_s'])} | {fresh} | "
            f"{num(1e6 * r['gradient_s'])} | {num(1e6 * r['step_s'])} |"
        )
    return "\n".join(out)
