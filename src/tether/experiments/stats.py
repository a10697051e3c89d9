"""Statistics of sweep results: mean, standard deviation, 95 % CI, and a test between groups.

Everything is computed with :mod:`scipy.stats` from the trials' values, never quoted.
The test between groups is chosen by the data and named in the result:

* every group looks normal (Shapiro-Wilk p >= 0.05 for each group of 3 or more
  values, and no group is constant):

  - 2 groups: Welch's t-test (unequal variances), effect size Hedges' g (Cohen's d
    with the small-sample correction; d is given too);
  - more groups: one-way ANOVA, effect size eta squared (between-group sum of
    squares over the total);

* normality doubtful (a Shapiro-Wilk p < 0.05, a constant group, or fewer than 3
  values in a group):

  - 2 groups: Mann-Whitney U (two-sided), effect size the rank-biserial
    correlation ``2 U1 / (n1 n2) - 1`` (positive: the first group tends larger);
  - more groups: Kruskal-Wallis H, effect size epsilon squared ``H / (n - 1)``.

Trials of a sweep are paired by seed (one seed, one random start on every
combination); these tests treat groups as independent samples, which ignores the
pairing and is conservative when paired trials are positively correlated.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy import stats

__all__ = ["Described", "GroupTest", "compare_groups", "describe"]

#: a Shapiro-Wilk p-value below this makes normality doubtful
NORMALITY_ALPHA = 0.05


@dataclass(frozen=True)
class Described:
    """Mean, sample standard deviation (ddof 1) and a t confidence interval of the mean."""

    n: int
    mean: float
    std: float
    ci_low: float
    ci_high: float
    confidence: float = 0.95


@dataclass(frozen=True)
class GroupTest:
    """A test between groups: its name, statistic, p-value, effect size and why it was chosen."""

    test: str
    statistic: float
    p_value: float
    effect_name: str
    effect: float
    reason: str
    extra: str = ""


def describe(values: Sequence[float] | np.ndarray, confidence: float = 0.95) -> Described:
    """Mean, standard deviation and the Student-t confidence interval of the mean.

    Parameters
    ----------
    values : array_like
        Finite values (NaN are dropped).
    confidence : float
        The interval's coverage, 0.95 for a 95 % CI.

    Returns
    -------
    Described
        With ``std`` and the interval NaN for fewer than 2 values.
    """
    x = np.asarray(values, dtype=float)
    x = x[np.isfinite(x)]
    n = int(x.size)
    if n == 0:
        return Described(0, math.nan, math.nan, math.nan, math.nan, confidence)
    mean = float(x.mean())
    if n < 2:
        return Described(n, mean, math.nan, math.nan, math.nan, confidence)
    std = float(x.std(ddof=1))
    half = float(stats.t.ppf(0.5 + confidence / 2, n - 1)) * std / math.sqrt(n)
    return Described(n, mean, std, mean - half, mean + half, confidence)


def _normality_doubt(groups: list[np.ndarray]) -> str | None:
    """Why normality is doubtful for these groups (None if every group looks normal)."""
    for k, g in enumerate(groups):
        if g.size < 3:
            return f"group {k + 1} has fewer than 3 values"
        if np.ptp(g) == 0:
            return f"group {k + 1} is constant"
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            p = float(stats.shapiro(g).pvalue)
        if p < NORMALITY_ALPHA:
            return f"Shapiro-Wilk p = {p:.3g} < {NORMALITY_ALPHA} in group {k + 1}"
    return None


def hedges_g(a: np.ndarray, b: np.ndarray) -> tuple[float, float]:
    """Cohen's d (pooled standard deviation) and Hedges' g (small-sample corrected) of a - b."""
    n1, n2 = a.size, b.size
    pooled = math.sqrt(((n1 - 1) * a.var(ddof=1) + (n2 - 1) * b.var(ddof=1)) / (n1 + n2 - 2))
    d = (a.mean() - b.mean()) / pooled if pooled > 0 else math.nan
    correction = 1 - 3 / (4 * (n1 + n2) - 9)
    return float(d), float(d * correction)


def compare_groups(groups: Mapping[str, Sequence[float] | np.ndarray]) -> GroupTest | None:
    """The fitting test between two or more groups, with its effect size.

    Parameters
    ----------
    groups : mapping of str to array_like
        Values by group label; NaN are dropped, groups with fewer than 2 values too.

    Returns
    -------
    GroupTest or None
        None when fewer than 2 groups have 2 or more values, or all values are equal.
    """
    data = [np.asarray(v, dtype=float) for v in groups.values()]
    data = [g[np.isfinite(g)] for g in data]
    data = [g for g in data if g.size >= 2]
    if len(data) < 2 or np.ptp(np.concatenate(data)) == 0:
        return None
    doubt = _normality_doubt(data)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        if doubt is None and len(data) == 2:
            res = stats.ttest_ind(data[0], data[1], equal_var=False)
            d, g = hedges_g(data[0], data[1])
            return GroupTest("Welch's t-test", float(res.statistic), float(res.pvalue),
                             "Hedges' g", g, "two groups, each normal (Shapiro-Wilk)",
                             f"Cohen's d = {d:.3g}")  # fmt: skip
        if doubt is None:
            res = stats.f_oneway(*data)
            allv = np.concatenate(data)
            ss_total = float(((allv - allv.mean()) ** 2).sum())
            ss_between = float(sum(g.size * (g.mean() - allv.mean()) ** 2 for g in data))
            return GroupTest("one-way ANOVA", float(res.statistic), float(res.pvalue),
                             "eta squared", ss_between / ss_total,
                             f"{len(data)} groups, each normal (Shapiro-Wilk)")  # fmt: skip
        if len(data) == 2:
            res = stats.mannwhitneyu(data[0], data[1], alternative="two-sided")
            r = 2 * float(res.statistic) / (data[0].size * data[1].size) - 1
            return GroupTest("Mann-Whitney U", float(res.statistic), float(res.pvalue),
                             "rank-biserial r", r, f"normality doubtful: {doubt}")  # fmt: skip
        res = stats.kruskal(*data)
        n = sum(g.size for g in data)
        return GroupTest("Kruskal-Wallis H", float(res.statistic), float(res.pvalue),
                         "epsilon squared", float(res.statistic) / (n - 1),
                         f"normality doubtful: {doubt}")  # fmt: skip
