"""Statistics of a sweep checked against values computed by hand (not by the same code)."""

from __future__ import annotations

import math

import pytest

from tether.experiments.stats import compare_groups, describe


def test_mean_std_and_95_ci_by_hand():
    values = [2, 4, 4, 4, 5, 5, 7, 9]
    # mean 40 / 8 = 5; squared deviations 9+1+1+1+0+0+4+16 = 32; s = sqrt(32 / 7)
    s = math.sqrt(32 / 7)
    t_975_7 = 2.364624  # Student t, 7 degrees of freedom, 97.5 % quantile (printed tables)
    half = t_975_7 * s / math.sqrt(8)
    d = describe(values)
    assert d.n == 8 and d.mean == 5
    assert d.std == pytest.approx(s, rel=1e-12)
    assert (d.ci_low, d.ci_high) == pytest.approx((5 - half, 5 + half), abs=1e-5)


def test_one_value_has_no_spread_and_nan_are_dropped():
    d = describe([3.0, float("nan")])
    assert d.n == 1 and d.mean == 3.0 and math.isnan(d.std) and math.isnan(d.ci_low)


def test_one_way_anova_by_hand():
    groups = {"a": [1, 2, 3], "b": [4, 5, 6], "c": [7, 8, 9]}
    # grand mean 5; SS between = 3 (16 + 0 + 16)... per group: 3 * ((2-5)^2 + 0 + (8-5)^2) = 54
    # SS within = 3 groups x (1 + 0 + 1) = 6; F = (54 / 2) / (6 / 6) = 27
    # for F(2, d2) the upper tail is exactly (1 + 2 F / d2) ** (-d2 / 2) = (1 + 9) ** -3
    res = compare_groups(groups)
    assert res is not None and res.test == "one-way ANOVA"
    assert res.statistic == pytest.approx(27.0)
    assert res.p_value == pytest.approx(10.0**-3)
    assert res.effect_name == "eta squared" and res.effect == pytest.approx(54 / 60)


def test_welch_t_and_hedges_g_by_hand():
    a, b = [1.0, 2.0, 3.0, 4.0], [2.0, 4.0, 6.0, 8.0]
    # means 2.5 and 5; variances 5/3 and 20/3; t = -2.5 / sqrt((5/3 + 20/3) / 4)
    t = -2.5 / math.sqrt((5 / 3 + 20 / 3) / 4)
    pooled = math.sqrt((5 / 3 + 20 / 3) / 2)
    g = (-2.5 / pooled) * (1 - 3 / (4 * 8 - 9))
    res = compare_groups({"a": a, "b": b})
    assert res is not None and res.test == "Welch's t-test"
    assert res.statistic == pytest.approx(t)
    assert res.effect_name == "Hedges' g" and res.effect == pytest.approx(g)
    assert 0.05 < res.p_value < 0.2  # |t| = 1.73 on about 4.4 degrees of freedom


def test_mann_whitney_when_normality_is_doubtful():
    # 2 values cannot be checked for normality -> Mann-Whitney; every a below every b:
    # U1 = 0, rank-biserial -1; exact two-sided p = 2 / C(5, 2) = 0.2
    res = compare_groups({"a": [1, 2], "b": [4, 5, 6]})
    assert res is not None and res.test == "Mann-Whitney U"
    assert res.statistic == 0 and res.effect == -1
    assert res.p_value == pytest.approx(0.2)
    assert "fewer than 3" in res.reason
    # a constant group makes normality doubtful too; b above a: r = +1
    res = compare_groups({"b": [4, 5, 6, 7], "a": [1, 1, 1]})
    assert res is not None and res.test == "Mann-Whitney U" and res.effect == 1
    assert "constant" in res.reason


def test_kruskal_wallis_for_more_groups_that_are_not_normal():
    res = compare_groups({"a": [1, 1, 1], "b": [2, 3, 4], "c": [5, 6, 7]})
    # ranks: a 2,2,2 (ties) b 4,5,6 c 7,8,9; n = 9
    assert res is not None and res.test == "Kruskal-Wallis H"
    assert res.effect == pytest.approx(res.statistic / 8)


def test_nothing_to_compare():
    assert compare_groups({"a": [1, 2, 3]}) is None
    assert compare_groups({"a": [2, 2], "b": [2, 2]}) is None
