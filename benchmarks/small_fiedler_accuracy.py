"""The small Fiedler solver on the eigenproblems of real runs, against LAPACK ``dsyevr``.

Runs ``multi_target_empty`` (300 steps) and ``multi_target_town`` (600 steps) with 35
robots, records every ``(Laplacian, guess)`` the strategy hands to ``fiedler`` with a
guess, and solves each again with :func:`tether.graph.small.small_fiedler` and with
``dsyevr`` (``fiedler(method="subset")``): how often the certificate holds, solves and
factorizations per call, and the differences in lambda2 (relative to the largest
degree) and in the vector (largest entry). The vector error estimate of each side is its
residual in extended precision divided by ``lambda3 - lambda2``.

    python benchmarks/small_fiedler_accuracy.py [--out PATH]
"""

from __future__ import annotations

import argparse
import json
import tempfile
from pathlib import Path

import numpy as np

import tether.continuous.weights as weights_module
from tether.config import apply_overrides, read_scenario_data
from tether.graph import small
from tether.graph.fiedler import _subset
from tether.runner import run

OUT = Path(__file__).parent / "results" / "small_fiedler_accuracy.json"
RUNS = (("multi_target_empty", 300), ("multi_target_town", 600))


def record(name: str, steps: int, n_robots: int = 35) -> list[tuple[np.ndarray, np.ndarray]]:
    """``(laplacian, guess)`` of every guessed eigenproblem of one run."""
    calls: list[tuple[np.ndarray, np.ndarray]] = []
    original = weights_module.fiedler

    def spy(n, pairs, w, guess=None, laplacian=None, **kw):  # noqa: ANN001, ANN202
        if guess is not None and n > 16:
            lap = laplacian if laplacian is not None else weights_module.laplacian_dense(
                n, pairs, w)  # fmt: skip
            calls.append((lap.copy(), np.array(guess, dtype=float)))
        return original(n, pairs, w, guess=guess, laplacian=laplacian, **kw)

    data, src, _ = read_scenario_data(name)
    data = apply_overrides(data, [f"team.n_robots={n_robots}", f"sim.max_steps={steps}"], src)
    weights_module.fiedler = spy
    try:
        with tempfile.TemporaryDirectory() as tmp:
            run(data, out_dir=Path(tmp) / "run", figures=False)
    finally:
        weights_module.fiedler = original
    return calls


def residual_error(lap: np.ndarray, vec: np.ndarray, gap: float) -> float:
    """``||L v - theta v|| / gap`` in extended precision (an estimate of the vector error)."""
    big = lap.astype(np.longdouble)
    x = vec.astype(np.longdouble)
    x = x / np.sqrt((x * x).sum())
    lx = big @ x
    theta = (x * lx).sum()
    return float(np.sqrt(((lx - theta * x) ** 2).sum()) / gap)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=OUT)
    a = ap.parse_args()
    problems = [p for name, steps in RUNS for p in record(name, steps)]
    status, solves, factors, dlam, dvec, mine, ref = [], [], [], [], [], [], []
    for lap, guess in problems:
        s, lam, vec, k, f = small.small_fiedler(lap, guess)
        status.append(int(s))
        if s != small.OK:
            continue
        solves.append(k)
        factors.append(f)
        n = len(guess)
        ref_lam, ref_vec = _subset(n, None, None, lap)
        ref_vec = ref_vec * (1.0 if float(ref_vec @ vec) >= 0 else -1.0)
        dlam.append(abs(lam - ref_lam) / float(np.max(np.diagonal(lap))))
        dvec.append(float(np.max(np.abs(vec - ref_vec))))
        vals = np.linalg.eigvalsh(lap)
        mine.append(residual_error(lap, vec, vals[2] - vals[1]))
        ref.append(residual_error(lap, ref_vec, vals[2] - vals[1]))
    pct = (50, 90, 99, 100)
    result = {
        "runs": [f"{name} 35 robots {steps} steps" for name, steps in RUNS],
        "problems": len(problems),
        "status_counts": {str(k): status.count(k) for k in sorted(set(status))},
        "status_names": "0 certified, 2 tiny, 3 breakdown, 4 inertia, 5 no convergence",
        "solves_per_call": np.bincount(solves).tolist(),
        "factorizations_per_call": np.bincount(factors).tolist(),
        "lambda2_diff_over_max_degree_max": max(dlam),
        "vector_max_abs_diff_percentiles_50_90_99_100": np.percentile(dvec, pct).tolist(),
        "vector_error_estimate_small_percentiles": np.percentile(mine, pct).tolist(),
        "vector_error_estimate_dsyevr_percentiles": np.percentile(ref, pct).tolist(),
    }
    a.out.parent.mkdir(parents=True, exist_ok=True)
    a.out.write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
