"""Statistics with hand-computed cases."""

import numpy as np
import pytest

from confront.experiments.stats import bootstrap_ci, hedges_g, interval, permutation_test


def test_bootstrap_of_constant_is_that_constant() -> None:
    m, lo, hi = bootstrap_ci(np.full((5, 3), 2.5), np.random.default_rng(0))
    np.testing.assert_allclose([m, lo, hi], np.full((3, 3), 2.5))


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


def test_monte_carlo_permutation_detects_and_does_not_invent() -> None:
    rng = np.random.default_rng(2)
    a, b = rng.normal(1.0, 0.5, 15), rng.normal(0.0, 0.5, 15)
    assert permutation_test(a, b, rng) < 0.01
    assert permutation_test(b, a, rng) > 0.9


def test_hedges_g_hand_computed() -> None:
    a, b = np.array([2.0, 4.0, 6.0]), np.array([1.0, 3.0, 5.0])
    # pooled sd = 2, d = 0.5, correction = 1 - 3 / (4*6 - 9) = 0.8
    assert hedges_g(a, b) == pytest.approx(0.4)
