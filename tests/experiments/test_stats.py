"""Statistics with hand-computed cases, and against SciPy where a function wraps it."""

import numpy as np
import pytest
from scipy import stats

from confront.stats import (
    bootstrap_ci,
    hedges_g,
    interval,
    mde_sign,
    mde_t,
    median_ci,
    paired_comparison,
    paired_permutation_test,
    permutation_test,
    sign_test,
)


def test_bootstrap_of_constant_is_that_constant() -> None:
    m, lo, hi = bootstrap_ci(np.full((5, 3), 2.5), np.random.default_rng(0))
    np.testing.assert_allclose([m, lo, hi], np.full((3, 3), 2.5))


def test_bootstrap_is_scipys_bca_per_column_and_drops_nans() -> None:
    x = np.random.default_rng(3).normal(0.0, 1.0, (12, 2))
    x[0, 1] = np.nan
    m, lo, hi = bootstrap_ci(x, np.random.default_rng(5), n_boot=999)
    rng = np.random.default_rng(5)
    for k in range(2):
        col = x[:, k][np.isfinite(x[:, k])]
        ci = stats.bootstrap((col,), np.mean, method="BCa", n_resamples=999, random_state=rng).confidence_interval
        assert (m[k], lo[k], hi[k]) == pytest.approx((col.mean(), ci.low, ci.high))


def test_bootstrap_interval_covers_mean_and_narrows_with_n() -> None:
    rng = np.random.default_rng(1)
    small = rng.normal(1.0, 1.0, 10)
    big = rng.normal(1.0, 1.0, 1000)
    a, b = interval(small, rng), interval(big, rng)
    assert a.lo < small.mean() < a.hi
    assert (b.hi - b.lo) < (a.hi - a.lo) / 5
    assert b.lo < 1.0 < b.hi


def test_exact_permutation_p_value() -> None:
    # a = {3, 4}, b = {1, 2}: of the C(4,2) = 6 relabellings only {3,4} gives a difference >= 2 -> p = 1/6
    p = permutation_test(np.array([3.0, 4.0]), np.array([1.0, 2.0]), np.random.default_rng(0))
    assert p == pytest.approx(1 / 6)
    p2 = permutation_test(np.array([3.0, 4.0]), np.array([1.0, 2.0]), np.random.default_rng(0), alternative="two-sided")
    assert p2 == pytest.approx(2 / 6)
    with pytest.raises(ValueError, match="alternative"):
        permutation_test(np.ones(2), np.ones(2), np.random.default_rng(0), alternative="bigger")


def test_exact_paired_permutation_p_value() -> None:
    # differences (1, 2, 3): of the 2^3 sign flips only (+, +, +) has a mean >= 2 -> p = 1/8
    p = paired_permutation_test(np.array([2.0, 3.0, 4.0]), np.array([1.0, 1.0, 1.0]), np.random.default_rng(0))
    assert p == pytest.approx(1 / 8)
    # (1, -2, 3), sum 2: the flips with a sum >= 2 are (1, -2, 3), (1, 2, 3) and (-1, 2, 3) -> p = 3/8
    p = paired_permutation_test(np.array([2.0, -1.0, 4.0]), np.array([1.0, 1.0, 1.0]), np.random.default_rng(0))
    assert p == pytest.approx(3 / 8)
    assert np.isnan(paired_permutation_test(np.ones(1), np.zeros(1), np.random.default_rng(0)))  # one pair: no test
    with pytest.raises(ValueError, match="one value per seed"):
        paired_permutation_test(np.ones(3), np.ones(2), np.random.default_rng(0))


def test_monte_carlo_permutation_detects_and_does_not_invent() -> None:
    rng = np.random.default_rng(2)
    a, b = rng.normal(1.0, 0.5, 15), rng.normal(0.0, 0.5, 15)
    assert permutation_test(a, b, rng) < 0.01
    assert permutation_test(b, a, rng) > 0.9


def test_hedges_g_hand_computed_and_from_scipys_t() -> None:
    a, b = np.array([2.0, 4.0, 6.0]), np.array([1.0, 3.0, 5.0])
    # pooled sd = 2, d = 0.5, correction = 1 - 3 / (4*6 - 9) = 0.8
    assert hedges_g(a, b) == pytest.approx(0.4)
    x, y = np.random.default_rng(4).normal(0, 1, 7), np.random.default_rng(5).normal(0.5, 2, 9)
    t = stats.ttest_ind(x, y).statistic  # d = t sqrt(1/na + 1/nb)
    assert hedges_g(x, y) == pytest.approx(t * np.sqrt(1 / 7 + 1 / 9) * (1 - 3 / (4 * 16 - 9)))


def test_detectable_difference_of_a_t_test() -> None:
    # many degrees of freedom: z_0.95 + z_0.8 = 1.6449 + 0.8416 standard errors
    assert mde_t(1.0, 1e7) == pytest.approx(2.4865, abs=1e-3)
    assert mde_t(2.0, 1e7, two_sided=True) == pytest.approx(2 * (1.9600 + 0.8416), abs=2e-3)
    assert mde_t(0.0, 9) == 0.0 and np.isnan(mde_t(1.0, 0))
    # paired, n = 10, sd 1: a one-sided t test at that true mean rejects in 80% of samples
    d = mde_t(1 / np.sqrt(10), 9)
    assert d == pytest.approx(0.853, abs=2e-3)  # G*Power: one-tailed, alpha .05, power .8, n = 10 -> dz 0.85
    x = np.random.default_rng(6).normal(d, 1.0, (20000, 10))
    t = x.mean(axis=1) / (x.std(axis=1, ddof=1) / np.sqrt(10))
    assert (t > stats.t.isf(0.05, 9)).mean() == pytest.approx(0.8, abs=0.01)


def test_detectable_share_of_a_sign_test() -> None:
    # n = 10: P(X >= 9 | 1/2) = 11/1024 <= 0.05 < P(X >= 8) = 56/1024, so the test rejects at 9 or 10;
    # power at share p is 10 p^9 (1 - p) + p^10
    p = mde_sign(10)
    assert 10 * p**9 * (1 - p) + p**10 == pytest.approx(0.8)
    assert p == pytest.approx(0.9167, abs=1e-4)
    assert np.isnan(mde_sign(3))  # P(X >= 3 | 1/2) = 1/8 > 0.05: no share is detectable
    assert mde_sign(1000) == pytest.approx(0.5 + (1.6449 + 0.8416) / 2 / np.sqrt(1000), abs=3e-3)


def test_sign_test_counts_ties_and_censored_runs() -> None:
    a = np.array([1.0, 2.0, 3.0, 4.0, 5.0, np.inf, 7.0, np.nan])
    b = np.array([2.0, 3.0, 4.0, 5.0, 6.0, np.inf, np.inf, 1.0])
    st = sign_test(a, b)  # 6 pairs a < b (the last with b censored), 1 tie (both censored), NaN dropped
    assert (st.less, st.equal, st.greater, st.n) == (6, 1, 0, 7)
    assert st.p == pytest.approx(0.5**6)
    assert st.share.mean == 1.0 and st.share.hi == 1.0
    assert st.share.lo == pytest.approx(0.025 ** (1 / 6))  # Clopper-Pearson, 6 of 6: (alpha / 2)^(1/n)
    two = sign_test(a, b, alternative="two-sided")
    assert two.p == pytest.approx(2 * 0.5**6)
    none = sign_test(np.ones(3), np.ones(3))
    assert none.p == 1.0 and np.isnan(none.mde)


def test_median_interval_is_the_order_statistics_one() -> None:
    # n = 10: [x_(2), x_(9)] has coverage 1 - 2 P(X <= 1 | Bin(10, 1/2)) = 1 - 22/1024 = 97.9% >= 95%,
    # [x_(3), x_(8)] only 1 - 2 * 56/1024 = 89.1%
    m = median_ci(np.arange(1.0, 11.0))
    assert (m.mean, m.lo, m.hi) == (5.0, 2.0, 9.0)
    inf = median_ci(np.array([-np.inf, -np.inf, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, np.inf, np.inf, np.nan]))
    assert inf.mean == 3.0 and inf.lo == -np.inf and inf.hi == np.inf
    few = median_ci(np.array([1.0, 2.0, 3.0, 4.0]))  # 2 * 1/16 > 5%: no order statistics give 95%
    assert few.mean == 2.0 and np.isnan(few.lo) and np.isnan(few.hi)


def test_paired_comparison_hand_computed() -> None:
    a, b = np.array([2.0, 4.0, 6.0, 8.0]), np.array([1.0, 2.0, 3.0, 4.0])
    res = paired_comparison(a, b, np.random.default_rng(0))
    # differences 1, 2, 3, 4: mean 2.5, sd sqrt(5/3); only the all-positive flip reaches 2.5 -> p = 1/16
    assert res.diff.mean == 2.5 and res.n == 4
    assert res.p == pytest.approx(1 / 16)
    assert res.dz == pytest.approx(2.5 / np.sqrt(5 / 3))
    assert res.mde == pytest.approx(mde_t(np.sqrt(5 / 3) / 2, 3))
    assert res.diff.lo < 2.5 < res.diff.hi
