"""Figures of docs/explanation/continuous.md: lambda2 over time in three scenes, the town.

Runs the builtin scenarios ``connectivity_empty``, ``connectivity_office`` and
``connectivity_town`` (into a temporary folder), reads the recorded
trajectories and recomputes, independently of the strategy's bookkeeping, the
weighted graph ``G_lambda`` of every recorded step (exact lambda2, smallest
robot distance and obstacle clearance).

Usage::

    python benchmarks/plot_continuous_figures.py

Writes ``docs/figures/continuous_lambda2.png`` and
``docs/figures/continuous_town_top.png``.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pyarrow.parquet as pq  # noqa: E402

from tether.config import load_scenario  # noqa: E402
from tether.continuous.connectivity.strategy import ConnectivityStrategyParams  # noqa: E402
from tether.continuous.connectivity.weights import compute_weights
from tether.runner import build, run  # noqa: E402
from tether.world.clearance import ObstacleIndex

FIGURES = Path(__file__).resolve().parents[1] / "docs" / "figures"
SCENES = ("connectivity_empty", "connectivity_office", "connectivity_town")


def trajectories(folder: Path, n: int) -> tuple[np.ndarray, np.ndarray]:
    """``(steps,)`` times and ``(steps, n, 3)`` positions of a run folder."""
    rob = pq.read_table(folder / "robots.parquet").to_pydict()
    steps = np.asarray(rob["step"])
    robot = np.asarray(rob["robot"])
    xyz = np.stack([rob["x_m"], rob["y_m"], rob["z_m"]], axis=1)
    order = np.lexsort((robot, steps))
    pos = xyz[order].reshape(-1, n, 3)
    t = pq.read_table(folder / "steps.parquet").to_pydict()["t_s"]
    return np.asarray(t)[: len(pos)], pos


def main() -> None:
    FIGURES.mkdir(parents=True, exist_ok=True)
    runs = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name in SCENES:
            sc = load_scenario(name)
            world = build(sc).world
            params = ConnectivityStrategyParams.model_validate(sc.strategy.params)
            conn = params.connectivity()
            out = run(sc, out_dir=Path(tmp) / name, figures=False)
            t, pos = trajectories(out.path, sc.team.n_robots)
            if len(t) != len(pos):  # steps.parquet may hold one record fewer than robots
                t = np.arange(len(pos)) * sc.sim.dt_s
            obs = ObstacleIndex.from_world(world)
            lam = np.array([compute_weights(q, conn, obs).fiedler()[0] for q in pos])
            runs[name] = (t, pos, lam, world, conn, out.summary)
            print(f"{name}: min lambda2 = {lam.min():.4f}, steps = {len(pos)}")

    fig, ax = plt.subplots(figsize=(7, 3.6))
    conn = runs["connectivity_town"][4]  # lambda2_min/null are equal in all three presets
    for name, (t, _, lam, _, _, summary) in runs.items():
        label = f"{name.split('_')[1]} ({summary['eigensolver']})"
        ax.plot(t, lam, label=label)
    ax.axhline(conn.lambda2_null, color="grey", ls="--", lw=0.8)
    ax.text(22, conn.lambda2_null + 0.08, r"$\lambda_2^{null}$ = 1: no force above", color="grey")
    ax.axhline(0.0, color="black", lw=0.8)
    ax.set_xlabel("time (s)")
    ax.set_ylabel(r"$\lambda_2$ of $G_\lambda$ (exact, recomputed)")
    ax.set_title("Random pulls / operator pull vs. the generalized connectivity force")
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(FIGURES / "continuous_lambda2.png", dpi=120)
    plt.close(fig)

    t, pos, lam, world, conn, _ = runs["connectivity_town"]
    grid = world.grid
    lo, hi = pos[..., :2].min(axis=(0, 1)) - 8, pos[..., :2].max(axis=(0, 1)) + 8
    # obstacles seen from above, up to the highest flight altitude
    top = int(np.ceil(pos[..., 2].max() / grid.resolution_m))
    occ = grid.occupied[:, :, : max(top, 1)].any(axis=2)
    ext = [grid.origin_m[0], grid.origin_m[0] + occ.shape[0] * grid.resolution_m,
           grid.origin_m[1], grid.origin_m[1] + occ.shape[1] * grid.resolution_m]  # fmt: skip
    fig, ax = plt.subplots(figsize=(7, 6))
    ax.imshow(occ.T, origin="lower", extent=ext, cmap="Greys", alpha=0.6)
    for k in range(pos.shape[1]):
        ax.plot(pos[:, k, 0], pos[:, k, 1], lw=0.8)
    final = pos[-1]
    graph = compute_weights(final, conn, ObstacleIndex.from_world(world))
    pairs, w = graph.active()
    for (a, b), wk in zip(pairs, w, strict=True):
        ax.plot(*final[[a, b], :2].T, color="tab:red", lw=0.5 + 2 * wk, alpha=0.8)
    ax.scatter(pos[0, :, 0], pos[0, :, 1], marker="o", facecolors="none", edgecolors="k",
               label="start")  # fmt: skip
    ax.scatter(final[:, 0], final[:, 1], color="k", s=14, label="end")
    ax.plot([], [], color="tab:red", label=r"final links of $G_\lambda$ (width ~ $W_{ij}$)")
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(f"Town, {pos.shape[1]} robots, 30 s of random pulls (min lambda2 {lam.min():.3f})")
    ax.legend(loc="upper right", fontsize=8)
    fig.tight_layout()
    fig.savefig(FIGURES / "continuous_town_top.png", dpi=120)
    plt.close(fig)
    print(f"wrote {FIGURES}/continuous_lambda2.png and continuous_town_top.png")


if __name__ == "__main__":
    main()
