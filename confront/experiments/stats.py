"""Statistics over seeds: bootstrap intervals, permutation tests, effect sizes.

Every function takes per-seed values (one number per independent run), so seeds, not rounds, are the unit.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Interval:
    """A mean with its bootstrap interval."""

    mean: float
    lo: float
    hi: float

    def __str__(self) -> str:
        return f"{self.mean:.3f} [{self.lo:.3f}, {self.hi:.3f}]"


def bootstrap_ci(values: np.ndarray, rng: np.random.Generator, level: float = 0.95, n_boot: int = 4000
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Mean and percentile-bootstrap interval of the mean over axis 0 (seeds), for every other column.

    ``values`` is ``(S,)`` or ``(S, K)``; NaNs (e.g. a seed without that session) are ignored per column.
    """
    x = np.asarray(values, dtype=np.float64)
    squeeze = x.ndim == 1
    x = x.reshape(x.shape[0], -1)
    s = x.shape[0]
    idx = rng.integers(0, s, size=(n_boot, s))
    boots = np.nanmean(x[idx], axis=1)  # (n_boot, K)
    tail = (1.0 - level) / 2.0
    lo, hi = np.nanquantile(boots, [tail, 1.0 - tail], axis=0)
    mean = np.nanmean(x, axis=0)
    if squeeze:
        return mean[0], lo[0], hi[0]
    return mean, lo, hi


def interval(values: np.ndarray, rng: np.random.Generator, level: float = 0.95) -> Interval:
    """Mean and bootstrap interval of a 1-D sample."""
    m, lo, hi = bootstrap_ci(np.asarray(values, dtype=np.float64), rng, level)
    return Interval(float(m), float(lo), float(hi))


def permutation_test(a: np.ndarray, b: np.ndarray, rng: np.random.Generator, n_perm: int = 20000,
                     alternative: str = "greater") -> float:
    """p-value of mean(a) - mean(b) under random relabelling of the pooled sample.

    ``alternative`` is "greater" (a > b), "less" or "two-sided". Exact enumeration is used when the
    number of relabellings is at most ``n_perm``.
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    pooled = np.concatenate([a, b])
    n, na = pooled.size, a.size
    observed = a.mean() - b.mean()
    from math import comb

    if comb(n, na) <= n_perm:
        from itertools import combinations

        masks = np.zeros((comb(n, na), n), dtype=bool)
        for i, c in enumerate(combinations(range(n), na)):
            masks[i, list(c)] = True
    else:
        order = np.argsort(rng.random((n_perm, n)), axis=1)
        masks = np.zeros((n_perm, n), dtype=bool)
        np.put_along_axis(masks, order[:, :na], True, axis=1)
    sums = masks.astype(np.float64) @ pooled
    diffs = sums / na - (pooled.sum() - sums) / (n - na)
    eps = 1e-12 * max(1.0, abs(observed))
    if alternative == "greater":
        hits = diffs >= observed - eps
    elif alternative == "less":
        hits = diffs <= observed + eps
    elif alternative == "two-sided":
        hits = np.abs(diffs) >= abs(observed) - eps
    else:
        raise ValueError(f"alternative must be greater, less or two-sided, got {alternative!r}")
    return float(hits.mean())


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
