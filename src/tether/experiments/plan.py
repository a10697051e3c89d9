"""The trials of a sweep: combinations of the ``sweep:`` block x seeds, with stable ids.

A trial's id is the path of its run folder inside the sweep folder,
``<label>~<hash>/seed-<s>``: a readable label of the combination
(``n_robots=15,d0_m=8.0``), a short hash of its normalised values (so ``15.0`` and
``"15.0"`` are one value and one id) and the seed. Ids do not depend on the order of
the axes in the file, the other axes' values or the executor, so a sweep that grows by
a value or a seed keeps the trials it has.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from tether.config import (
    MAX_SEED,
    MAX_SWEEP_TRIALS,
    Scenario,
    scenario_from_dict,
    set_dotted,
    sweep_label,
    sweep_spec,
)
from tether.errors import ScenarioError, TetherError
from tether.experiments.executors import Trial
from tether.plugins import loaded_plugins
from tether.runner import build, check_sweep, strategy_class
from tether.sweepspec import combo_hash

__all__ = ["check_combinations", "combo_id", "seeds_of", "trial_id", "trial_scenario", "trials_of"]


def combo_id(combo: dict[str, Any], followers: set[str] | frozenset[str] = frozenset()) -> str:
    """The folder name of a combination: readable label, ``~`` and a short hash (``base``).

    The label leaves out ``followers`` (zipped axes named by their group's first axis,
    :meth:`tether.sweepspec.SweepSpec.followers`); the hash covers every value.
    """
    if not combo:
        return "base"
    shown = {k: v for k, v in combo.items() if k not in followers} or combo
    return f"{sweep_label(shown)}~{combo_hash(combo)}"


def trial_id(out_dir: str | Path, trial: Trial) -> str:
    """The id of a trial: its run folder relative to the sweep folder (``<combo>/seed-<s>``)."""
    return Path(trial.run_dir).relative_to(Path(out_dir)).as_posix()


def trial_scenario(base: Scenario, combo: dict[str, Any]) -> Scenario:
    """The scenario of one combination: ``base`` with the combination's values, no sweep."""
    data = base.model_dump(mode="json")
    data.pop("sweep", None)
    for key, value in combo.items():
        set_dotted(data, key, value)
    return scenario_from_dict(data, f"{base.source} [{sweep_label(combo)}]", base.base_dir)


def seeds_of(scenario: Scenario, seeds: int | list[int] | None = None) -> list[int]:
    """The seeds of a sweep: ``seeds`` (a count or a list), else the block's ``seeds``, else 1.

    A count ``n`` means the scenario's ``seed`` and the ``n - 1`` after it.
    """
    ok_count = isinstance(seeds, int) and not isinstance(seeds, bool) and seeds >= 1
    ok_list = isinstance(seeds, list) and bool(seeds) and all(
        isinstance(s, int) and not isinstance(s, bool) and 0 <= s <= MAX_SEED for s in seeds
    )  # fmt: skip
    if seeds is not None and not (ok_count or ok_list):
        raise ValueError(f"seeds must be a positive integer or a list of seeds (got {seeds!r})")
    spec = sweep_spec(scenario)
    count = seeds if seeds is not None else spec.seeds
    if isinstance(count, int) and count > MAX_SWEEP_TRIALS:  # refused before the list is made
        raise TetherError(
            f"{scenario.source}: sweep: seeds: {count:,} seeds; a sweep has at most "
            f"{MAX_SWEEP_TRIALS:,} trials (use fewer seeds)"
        )
    chosen = spec.seed_list(scenario.seed, seeds)
    if max(chosen) > MAX_SEED:
        raise TetherError(
            f"{scenario.source}: seed: {scenario.seed} + {len(chosen)} seeds passes 2**63 - 1; "
            "use a smaller seed"
        )
    return list(dict.fromkeys(chosen))


def trials_of(
    scenario: Scenario, out_dir: str | Path, seeds: int | list[int] | None = None
) -> list[tuple[dict[str, Any], Trial]]:
    """The sweep's trials with their (normalised) combination, in a stable order.

    Combinations in the order of :meth:`tether.sweepspec.SweepSpec.combinations`,
    each with every seed of :func:`seeds_of`; one run folder per trial,
    ``<out_dir>/<combo_id>/seed-<s>``.
    """
    seed_list = seeds_of(scenario, seeds)
    axes = check_sweep(scenario, strategy_class(scenario))
    spec = sweep_spec(scenario)
    combos, followers = spec.combinations(axes), spec.followers()
    if len(combos) * len(seed_list) > MAX_SWEEP_TRIALS:  # for --seeds (the block's: parsed)
        raise TetherError(
            f"{scenario.source}: sweep: {len(combos):,} combinations x {len(seed_list):,} seeds = "
            f"{len(combos) * len(seed_list):,} trials; at most {MAX_SWEEP_TRIALS:,} "
            "(use fewer seeds or values)"
        )
    out = Path(out_dir)
    plugins = loaded_plugins()  # imported again where each trial runs
    trials = []
    for combo in combos:
        trial = trial_scenario(scenario, combo)
        data = trial.model_dump(mode="json")
        folder = out / combo_id(combo, followers)
        for seed in seed_list:
            run_dir = str(folder / f"seed-{seed}")
            trial_ = Trial(data, trial.source, str(trial.base_dir), seed, run_dir, plugins)
            trials.append((combo, trial_))
    return trials


def check_combinations(scenario: Scenario, seeds: int | list[int] | None = None) -> int:
    """Build every combination at the sweep's first seed, as its trial will (no simulation).

    What ``tether validate`` and ``tether sweep`` check before any trial runs, so a sweep
    file that validates is one whose every combination starts: a zipped pair of values
    that cannot place the team, a team too large for the map, a run too large for memory.

    Returns
    -------
    int
        The number of combinations checked.

    Raises
    ------
    ScenarioError
        ``<file>: sweep: combination <label> is refused (<problem>)``.
    """
    seed = seeds_of(scenario, seeds)[0]
    axes = check_sweep(scenario, strategy_class(scenario))
    combos = sweep_spec(scenario).combinations(axes)
    if combos == [{}]:
        return 0
    for combo in combos:
        try:
            build(trial_scenario(scenario, combo), seed=seed)
        except TetherError as exc:
            problem = str(exc).split("]: ", 1)[-1]  # drop "<file> [<label>]: "
            raise ScenarioError(
                f"{scenario.source}: sweep: combination {sweep_label(combo)} (seed {seed}) is "
                f"refused ({problem})"
            ) from None
    return len(combos)
