"""APX on the plans of one run, with and without the pair filter.

    TETHER_JIT=on python benchmarks/bench_apx_plans.py recurrent_grass

Runs the scenario once (no figures) keeping every ``solve_apx`` call's problem, then
solves them all again with ``pair_filter`` off (the reference) and on: CPU time of the
144 plans (best of 3), the subsets costed by the shared DP per size (the rows asked of
``LazySteiner._evaluate``), and whether every result field but the work counter is
the same.
"""

from __future__ import annotations

import collections
import sys
import tempfile
import time
from pathlib import Path

from tether.recurrent.planning import apx, configuration
from tether.runner import run


def main() -> None:
    plans = []
    solve = configuration.solve_apx

    def keep(problem: object, delta: int) -> object:
        plans.append((problem, delta))
        return solve(problem, delta)

    configuration.solve_apx = keep
    with tempfile.TemporaryDirectory() as tmp:
        run(sys.argv[1], out_dir=Path(tmp) / "r", figures=False)
    configuration.solve_apx = solve
    rows = collections.Counter()
    evaluate = apx.LazySteiner._evaluate
    flag = False

    def counted(self: apx.LazySteiner, combos):  # noqa: ANN001, ANN202
        rows[(flag, combos.shape[1])] += len(combos)
        return evaluate(self, combos)

    results = {}
    for flag in (False, True):  # read by counted
        best = float("inf")
        for rep in range(3):
            apx.LazySteiner._evaluate = counted if rep == 0 else evaluate
            tic = time.process_time()
            out = [apx.solve_apx(p, d, pair_filter=flag) for p, d in plans]
            best = min(best, time.process_time() - tic)
        apx.LazySteiner._evaluate = evaluate
        results[flag] = [
            (r.vertices, r.utility, r.best_subset_utility, r.proven_optimal, r.upper_bound)
            for r in out
        ]
        sizes = ", ".join(
            f"{s}: {rows[(on, s)]:,}" for on, s in sorted(rows) if on == flag
        )  # fmt: skip
        print(f"pair_filter={flag}: {len(plans)} plans in {best:.3f} s; subsets costed {sizes}")
    print("same results:", results[False] == results[True])


if __name__ == "__main__":
    main()
