"""SMDP backup targets (Eq. 8-10) shared by the tabular learners and the DMNN."""

from __future__ import annotations

import numpy as np

__all__ = ["BACKUPS", "BOOTSTRAPS", "bootstrap_values", "intermediate_values", "smdp_target"]

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
