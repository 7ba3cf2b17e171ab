"""Parameter sharing (paper §4.2): every tank of a team acts through, and trains, one learner.

Tanks differ only through their own observations: a team's ``(B, R, ...)`` observations become the rows of
one batch, and the team's transitions one batch of ``learn`` (see ``Transition.from_team``).
"""

from __future__ import annotations

import numpy as np

from confront.learning.base import Learner, Transition

__all__ = ["team_act", "team_learn"]


def team_act(learner: Learner, obs: np.ndarray, rng: np.random.Generator, explore: bool = True) -> np.ndarray:
    """Actions ``(B, R)`` for ``(B, R)`` discrete or ``(B, R, F)`` feature observations of B battles' teams."""
    obs = np.asarray(obs)
    if obs.ndim < 2:
        raise ValueError(f"team observations must have shape (B, R, ...), got {obs.shape}")
    b, r = obs.shape[:2]
    return learner.act(obs.reshape((b * r,) + obs.shape[2:]), rng, explore).reshape(b, r)


def team_learn(learner: Learner, obs: np.ndarray, action: np.ndarray, rewards: np.ndarray,
               next_obs: np.ndarray, done: np.ndarray) -> dict[str, float]:
    """One shared update from every tank's transition: ``(B, R, ...)`` arrays, rewards ``(B, R, T)``."""
    return learner.learn(Transition.from_team(obs, action, rewards, next_obs, done))
