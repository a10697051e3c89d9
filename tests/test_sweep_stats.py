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


# -- unequal groups against p-values computed here, without scipy ------------------------


def t_two_sided_p(t: float, df: float, intervals: int = 20_000) -> float:
    """``P(|T| >= |t|)`` for Student's t with ``df`` degrees of freedom: 1 minus twice the
    density integrated over ``[0, |t|]`` (composite Simpson, error far below 1e-9)."""
    c = math.exp(math.lgamma((df + 1) / 2) - math.lgamma(df / 2)) / math.sqrt(df * math.pi)

    def pdf(x: float) -> float:
        return c * (1 + x * x / df) ** (-(df + 1) / 2)

    h = abs(t) / intervals
    odd = sum(pdf((2 * k - 1) * h) for k in range(1, intervals // 2 + 1))
    even = sum(pdf(2 * k * h) for k in range(1, intervals // 2))
    area = h / 3 * (pdf(0.0) + 4 * odd + 2 * even + pdf(abs(t)))
    return 1 - 2 * area


def mean_var(x: list[float]) -> tuple[float, float]:
    m = sum(x) / len(x)
    return m, sum((v - m) ** 2 for v in x) / (len(x) - 1)


def test_welch_not_student_on_unequal_groups():
    a = [10.1, 9.8, 10.3, 10.0, 9.9]  # 5 values, small spread
    b = [12.0, 14.5, 11.0, 16.0, 13.0, 15.5, 12.5]  # 7 values, large spread
    (ma, va), (mb, vb) = mean_var(a), mean_var(b)
    se_a, se_b = va / len(a), vb / len(b)
    t = (ma - mb) / math.sqrt(se_a + se_b)
    df = (se_a + se_b) ** 2 / (se_a**2 / (len(a) - 1) + se_b**2 / (len(b) - 1))
    pooled = ((len(a) - 1) * va + (len(b) - 1) * vb) / (len(a) + len(b) - 2)
    t_student = (ma - mb) / math.sqrt(pooled * (1 / len(a) + 1 / len(b)))
    p_student = t_two_sided_p(t_student, len(a) + len(b) - 2)
    res = compare_groups({"a": a, "b": b})
    assert res is not None and res.test == "Welch's t-test"
    assert res.statistic == pytest.approx(t, rel=1e-12)
    assert res.p_value == pytest.approx(t_two_sided_p(t, df), rel=1e-6)
    assert abs(res.p_value - p_student) > 1e-4 and abs(t - t_student) > 0.5  # told apart


def test_anova_on_groups_of_4_3_and_5_by_hand():
    groups = [[1.1, 2.3, 2.9, 3.6], [4.2, 5.0, 5.9], [5.5, 6.4, 7.1, 7.8, 8.9]]
    allv = [v for g in groups for v in g]
    grand = sum(allv) / len(allv)
    between = sum(len(g) * (sum(g) / len(g) - grand) ** 2 for g in groups)
    within = sum((v - sum(g) / len(g)) ** 2 for g in groups for v in g)
    d2 = len(allv) - 3
    f = (between / 2) / (within / d2)
    res = compare_groups(dict(zip("abc", groups, strict=True)))
    assert res is not None and res.test == "one-way ANOVA"
    assert res.statistic == pytest.approx(f, rel=1e-12)
    assert res.p_value == pytest.approx((1 + 2 * f / d2) ** (-d2 / 2), rel=1e-9)  # F(2, d2)
    assert res.effect == pytest.approx(between / (between + within), rel=1e-12)


def test_kruskal_wallis_on_groups_of_3_4_and_2_by_hand():
    groups = [[1.0, 1.5, 1.8], [2.5, 3.0, 4.2, 4.9], [5.1, 6.3]]  # no ties; 2 values: not normal
    n = 9
    ranks = {v: r for r, v in enumerate(sorted(v for g in groups for v in g), start=1)}
    h = 12 / (n * (n + 1)) * sum(sum(ranks[v] for v in g) ** 2 / len(g) for g in groups)
    h -= 3 * (n + 1)
    res = compare_groups(dict(zip("abc", groups, strict=True)))
    assert res is not None and res.test == "Kruskal-Wallis H"
    assert res.statistic == pytest.approx(h, rel=1e-12)
    assert res.p_value == pytest.approx(math.exp(-h / 2), rel=1e-9)  # chi-square, 2 df


def test_mann_whitney_exact_p_on_groups_of_2_and_6_by_enumeration():
    import itertools

    a, b = [1.0, 3.5], [2.0, 4.0, 5.0, 6.0, 7.0, 8.0]
    u1 = sum((x > y) + 0.5 * (x == y) for x in a for y in b)
    pooled = sorted(a + b)
    us = []  # U1 of every way to pick a's 2 ranks among 8
    for picked in itertools.combinations(range(8), 2):
        rank_sum = sum(k + 1 for k in picked)
        us.append(rank_sum - 2 * 3 / 2)
    mean_u = len(a) * len(b) / 2
    p = sum(abs(u - mean_u) >= abs(u1 - mean_u) for u in us) / len(us)
    res = compare_groups({"a": a, "b": b})
    assert res is not None and res.test == "Mann-Whitney U"
    assert res.statistic == u1 == 1 and len(pooled) == 8
    assert res.p_value == pytest.approx(p, rel=1e-12)
    assert res.effect == pytest.approx(2 * u1 / 12 - 1)
