"""Statistics over seeds: intervals, paired and unpaired tests, effect sizes and detectable effects.

Every function takes per-seed values (one number per independent run), so seeds, not rounds, are the unit.
SciPy does the resampling and the tests (``scipy.stats.bootstrap`` BCa, ``permutation_test``, ``binomtest``,
``quantile_test``); what SciPy lacks is here: Hedges' g and the minimum detectable effect at a given power.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import optimize, stats

__all__ = ["Interval", "Paired", "SignTest", "bootstrap_ci", "hedges_g", "interval", "mde_sign", "mde_t",
           "median_ci", "paired_comparison", "paired_permutation_test", "permutation_test", "sign_test", "t_interval"]

ALTERNATIVES = ("greater", "less", "two-sided")


@dataclass(frozen=True)
class Interval:
    """A mean (or median) with its 95% interval."""

    mean: float
    lo: float
    hi: float

    def __str__(self) -> str:
        return f"{self.mean:.3f} [{self.lo:.3f}, {self.hi:.3f}]"


def _check_alternative(alternative: str) -> None:
    if alternative not in ALTERNATIVES:
        raise ValueError(f"alternative must be greater, less or two-sided, got {alternative!r}")


def _bca_column(x: np.ndarray, rng: np.random.Generator, level: float, n_boot: int) -> tuple[float, float, float]:
    x = x[np.isfinite(x)]
    if x.size == 0:
        return float("nan"), float("nan"), float("nan")
    mean = float(x.mean())
    if x.size < 2 or np.ptp(x) == 0:  # nothing to resample: the interval is the value itself
        return mean, mean, mean
    ci = stats.bootstrap((x,), np.mean, confidence_level=level, n_resamples=n_boot, method="BCa",
                         random_state=rng).confidence_interval
    lo, hi = float(ci.low), float(ci.high)
    if not (np.isfinite(lo) and np.isfinite(hi)):  # BCa undefined (e.g. one value differs): percentile instead
        ci = stats.bootstrap((x,), np.mean, confidence_level=level, n_resamples=n_boot, method="percentile",
                             random_state=rng).confidence_interval
        lo, hi = float(ci.low), float(ci.high)
    return mean, lo, hi


def bootstrap_ci(values: np.ndarray, rng: np.random.Generator, level: float = 0.95, n_boot: int = 4000
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mean and BCa bootstrap interval of the mean over axis 0 (seeds), for every other column.

    ``values`` is ``(S,)`` or ``(S, K)``; NaNs (e.g. a seed without that session) are dropped per column; a
    column with one value or a constant one has the value itself as its interval.
    """
    x = np.asarray(values, dtype=np.float64)
    squeeze = x.ndim == 1
    x = x.reshape(x.shape[0], -1)
    cols = np.array([_bca_column(x[:, k], rng, level, n_boot) for k in range(x.shape[1])]).reshape(-1, 3)
    mean, lo, hi = cols[:, 0], cols[:, 1], cols[:, 2]
    if squeeze:
        return mean[0], lo[0], hi[0]
    return mean, lo, hi


def interval(values: np.ndarray, rng: np.random.Generator, level: float = 0.95) -> Interval:
    """Mean and BCa bootstrap interval of a 1-D sample."""
    m, lo, hi = bootstrap_ci(np.asarray(values, dtype=np.float64), rng, level)
    return Interval(float(m), float(lo), float(hi))


def _mean_diff(a: np.ndarray, b: np.ndarray, axis: int = -1) -> np.ndarray:
    return np.mean(a, axis=axis) - np.mean(b, axis=axis)


def permutation_test(a: np.ndarray, b: np.ndarray, rng: np.random.Generator, n_perm: int = 20000,
                     alternative: str = "greater") -> float:
    """Unpaired: p-value of mean(a) - mean(b) under random relabelling of the pooled sample (SciPy's
    ``permutation_test``, exact when there are at most ``n_perm`` relabellings)."""
    _check_alternative(alternative)
    res = stats.permutation_test((np.asarray(a, float), np.asarray(b, float)), _mean_diff, vectorized=True,
                                 permutation_type="independent", n_resamples=n_perm, alternative=alternative,
                                 random_state=rng)
    return float(res.pvalue)


def paired_permutation_test(a: np.ndarray, b: np.ndarray, rng: np.random.Generator, n_perm: int = 20000,
                            alternative: str = "greater") -> float:
    """Paired (seed i of ``a`` with seed i of ``b``): p-value of mean(a - b) when each pair's sign may flip
    (SciPy's ``permutation_test`` with ``permutation_type="samples"``, exact up to 2^n <= ``n_perm``); NaN for
    fewer than 2 pairs."""
    _check_alternative(alternative)
    a, b = np.asarray(a, float), np.asarray(b, float)
    if a.shape != b.shape:
        raise ValueError(f"paired samples need one value per seed in both, got {a.shape} and {b.shape}")
    if a.size < 2:
        return float("nan")
    res = stats.permutation_test((a, b), _mean_diff, vectorized=True, permutation_type="samples",
                                 n_resamples=n_perm, alternative=alternative, random_state=rng)
    return float(res.pvalue)


def hedges_g(a: np.ndarray, b: np.ndarray) -> float:
    """Standardised mean difference (a - b) with Hedges' small-sample correction; 0 when both are constant."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    na, nb = a.size, b.size
    if na < 2 or nb < 2:
        return float("nan")
    pooled = np.sqrt(((na - 1) * a.var(ddof=1) + (nb - 1) * b.var(ddof=1)) / (na + nb - 2))
    diff = a.mean() - b.mean()
    if pooled == 0:
        return 0.0 if diff == 0 else float(np.sign(diff) * np.inf)
    correction = 1.0 - 3.0 / (4.0 * (na + nb) - 9.0)
    return float(diff / pooled * correction)


def mde_t(se: float, df: float, alpha: float = 0.05, power: float = 0.8, two_sided: bool = False) -> float:
    """Smallest true difference a t-test with standard error ``se`` and ``df`` degrees of freedom detects with
    probability ``power`` at level ``alpha`` (noncentral t; the permutation test's power is close to it)."""
    if not (np.isfinite(se) and df >= 1):
        return float("nan")
    if se == 0:
        return 0.0
    crit = stats.t.isf(alpha / 2 if two_sided else alpha, df)
    # power(nc) = P(T' > crit), T' ~ noncentral t(df, nc = delta / se); solve power(nc) = power for nc
    nc = optimize.brentq(lambda c: stats.nct.sf(crit, df, c) - power, 0.0, 100.0)
    return float(nc * se)


def mde_sign(n: int, alpha: float = 0.05, power: float = 0.8, two_sided: bool = False) -> float:
    """Smallest share P(first < second) among ``n`` untied pairs that an exact sign test detects with
    probability ``power``; NaN when no share can (too few pairs)."""
    if n < 1:
        return float("nan")
    a = alpha / 2 if two_sided else alpha
    k = int(stats.binom.isf(a, n, 0.5)) + 1  # reject when X >= k: P(X >= k | 1/2) <= a
    if k > n:
        return float("nan")
    return float(optimize.brentq(lambda p: stats.binom.sf(k - 1, n, p) - power, 0.5, 1.0))


def t_interval(x: np.ndarray, level: float = 0.95) -> Interval:
    """Mean and Student-t interval of the mean, mean +- t(level, n-1) * s / sqrt(n) (NaN dropped; fewer than two
    values: NaN bounds, no spread to measure)."""
    x = np.asarray(x, dtype=np.float64)
    x = x[~np.isnan(x)]
    if x.size == 0:
        return Interval(float("nan"), float("nan"), float("nan"))
    mean = float(x.mean())
    if x.size < 2:
        return Interval(mean, float("nan"), float("nan"))
    half = float(stats.t.ppf(0.5 + level / 2, x.size - 1) * x.std(ddof=1) / np.sqrt(x.size))
    return Interval(mean, mean - half, mean + half)


def median_ci(x: np.ndarray, level: float = 0.95) -> Interval:
    """Median (the lower middle value) and its distribution-free interval (order statistics, SciPy's
    ``quantile_test``); +-inf allowed, NaN dropped."""
    x = np.asarray(x, dtype=np.float64)
    x = x[~np.isnan(x)]
    if x.size == 0:
        return Interval(float("nan"), float("nan"), float("nan"))
    ci = stats.quantile_test(x, p=0.5).confidence_interval(level)  # order statistics: does not depend on q
    return Interval(float(np.quantile(x, 0.5, method="lower")), float(ci.low), float(ci.high))


@dataclass(frozen=True)
class SignTest:
    """Paired sign test of "a < b": counts, one-sided p (ties dropped), the share of a < b among untied pairs
    with its Clopper-Pearson interval, and the share the test could detect at power 0.8."""

    less: int
    equal: int
    greater: int
    p: float
    share: Interval
    mde: float

    @property
    def n(self) -> int:
        return self.less + self.equal + self.greater


def sign_test(a: np.ndarray, b: np.ndarray, alternative: str = "less", level: float = 0.95,
              alpha: float = 0.05, power: float = 0.8) -> SignTest:
    """Sign test on pairs (a_i, b_i): is a < b (``less``), a > b (``greater``) or either (``two-sided``) more
    often than not? Values may be +inf (a censored run: later than any finite value); NaN pairs are dropped."""
    _check_alternative(alternative)
    a, b = np.asarray(a, float), np.asarray(b, float)
    keep = ~(np.isnan(a) | np.isnan(b))
    a, b = a[keep], b[keep]
    less, greater = int((a < b).sum()), int((a > b).sum())
    equal = int(a.size - less - greater)  # includes inf == inf: both censored, order unknown
    untied = less + greater
    if untied == 0:
        return SignTest(less, equal, greater, 1.0, Interval(float("nan"), 0.0, 1.0), float("nan"))
    side = {"less": "greater", "greater": "less", "two-sided": "two-sided"}[alternative]
    res = stats.binomtest(less, untied, 0.5, alternative=side)  # X = #(a < b) ~ Bin(untied, 1/2) under H0
    ci = stats.binomtest(less, untied, 0.5).proportion_ci(confidence_level=level, method="exact")  # two-sided CI
    mde = mde_sign(untied, alpha, power, two_sided=alternative == "two-sided")
    return SignTest(less, equal, greater, float(res.pvalue), Interval(less / untied, float(ci.low), float(ci.high)),
                    mde)


@dataclass(frozen=True)
class Paired:
    """Paired comparison of per-seed values: mean difference a - b with its BCa interval, the paired
    permutation p, the detectable difference at power 0.8 and the standardised difference d_z."""

    diff: Interval
    p: float
    mde: float
    n: int
    dz: float


def paired_comparison(a: np.ndarray, b: np.ndarray, rng: np.random.Generator, alternative: str = "greater",
                      level: float = 0.95, alpha: float = 0.05, power: float = 0.8) -> Paired:
    """Compare arms run on the same seeds: ``a - b`` per seed, tested with sign flips."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    d = a - b
    n = d.size
    p = paired_permutation_test(a, b, rng, alternative=alternative)
    sd = float(d.std(ddof=1)) if n > 1 else float("nan")
    mde = mde_t(sd / np.sqrt(n), n - 1, alpha, power, two_sided=alternative == "two-sided") if n > 1 else float("nan")
    dz = float(d.mean() / sd) if n > 1 and sd > 0 else float("nan")
    return Paired(interval(d, rng, level), p, mde, n, dz)
