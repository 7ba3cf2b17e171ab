"""SMDP backup targets (Eq. 8-10) shared by the tabular learners and the DMNN."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["BACKUPS", "BOOTSTRAPS", "bootstrap_values", "intermediate_values", "pairwise_sum", "paper_target_one",
           "smdp_target"]

BACKUPS = ("paper", "smdp")
BOOTSTRAPS = ("expected", "max")


def bootstrap_values(q_next: np.ndarray, probs: np.ndarray | None, done: np.ndarray) -> np.ndarray:
    """Value of the next state: sum_a pi(a|s') Q(s',a) when ``probs`` is given, else max_a Q(s',a); 0 if done."""
    if probs is None:
        v = q_next.max(axis=-1)  # Eq. 4: gamma max_a' Q(s', a')
    else:
        v = (probs * q_next).sum(axis=-1)  # Eq. 9: sum_a pi(a|s_{t+1}) Q(s_{t+1}, a)
    return np.where(done, 0.0, v)


def intermediate_values(rewards: np.ndarray, bootstrap: np.ndarray, gamma: float) -> np.ndarray:
    """The values Q_{t+i}, i = 0..T-1, backed up from the last one: ``(N, T)``."""
    n, t = rewards.shape
    out = np.empty((n, t))
    nxt = bootstrap
    for i in range(t - 1, -1, -1):
        nxt = rewards[:, i] + gamma * nxt  # Eq. 9 (i = T-1) and Eq. 8: Q_{t+i} = r_{t+i} + gamma Q_{t+i+1}
        out[:, i] = nxt
    return out


def smdp_target(rewards: np.ndarray, bootstrap: np.ndarray, gamma: float, backup: str) -> np.ndarray:
    """Target that Q(s_t, a_t) moves toward, one per row of ``rewards`` ``(N, T)``.

    ``paper``: (r_t + sum_{k=1}^{T-1} Q_{t+k}) / T (Eq. 10 read as a TD update; for T = 1 it is Q_t of Eq. 9,
    r_t + gamma V(s'), since Eq. 9 then defines Q_t itself). ``smdp``: sum_i gamma^i r_{t+i} + gamma^T V(s').
    """
    rewards = np.asarray(rewards, dtype=np.float64)
    t = rewards.shape[1]
    if backup == "smdp":
        disc = gamma ** np.arange(t)
        return rewards @ disc + gamma**t * bootstrap  # textbook SMDP backup: sum gamma^i r + gamma^T V(s')
    if backup != "paper":
        raise ValueError(f"bad value backup={backup!r}: must be one of {', '.join(BACKUPS)}")
    qs = intermediate_values(rewards, bootstrap, gamma)
    if t == 1:
        return qs[:, 0]
    return (rewards[:, 0] + qs[:, 1:].sum(axis=1)) / t  # Eq. 10: (r_t + sum_{k=1}^{T-1} Q_{t+k}) / T


def pairwise_sum(xs: Sequence[float], start: int = 0) -> float:
    """``np.sum`` of the float64 values ``xs[start:]`` computed on Python floats in NumPy's order, so it is the
    same double: the reduction starts from +0.0 and adds the pairwise sum of NumPy's add loop (a plain loop from
    -0.0 below 8 values, eight running sums up to 128, halves beyond). For the one-transition paths that must
    give the batched NumPy path's bits without its per-call cost (a test checks lengths 1-300 against np.sum)."""
    return 0.0 + _pairwise(xs, start, len(xs) - start)


def _pairwise(xs: Sequence[float], start: int, n: int) -> float:
    if n < 8:
        res = -0.0
        for i in range(start, start + n):
            res += xs[i]
        return res
    if n <= 128:
        r0, r1, r2, r3, r4, r5, r6, r7 = xs[start:start + 8]
        i, end = start + 8, start + n - n % 8
        while i < end:
            r0 += xs[i]
            r1 += xs[i + 1]
            r2 += xs[i + 2]
            r3 += xs[i + 3]
            r4 += xs[i + 4]
            r5 += xs[i + 5]
            r6 += xs[i + 6]
            r7 += xs[i + 7]
            i += 8
        res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
        for j in range(i, start + n):
            res += xs[j]
        return res
    half = n // 2
    half -= half % 8
    return _pairwise(xs, start, half) + _pairwise(xs, start + half, n - half)


def paper_target_one(rewards: Sequence[float], bootstrap: float, gamma: float) -> float:
    """``smdp_target`` with ``backup="paper"`` for one transition on Python floats: the same double."""
    t = len(rewards)
    qs = [0.0] * t
    nxt = bootstrap
    for i in range(t - 1, -1, -1):
        nxt = rewards[i] + gamma * nxt  # Eq. 9 and Eq. 8, as intermediate_values
        qs[i] = nxt
    if t == 1:
        return qs[0]
    return (rewards[0] + pairwise_sum(qs, 1)) / t  # Eq. 10
