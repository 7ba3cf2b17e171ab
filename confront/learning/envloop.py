"""Running a learner on any Gymnasium environment with a discrete action space (one agent, SMDP steps)."""

from __future__ import annotations

from typing import Any

import numpy as np

from confront.learning.base import Learner, Transition, check_int

__all__ = ["run_episodes"]


def _row(obs: Any, learner: Learner) -> np.ndarray:
    if learner.observation == "discrete":
        return np.array([int(obs)], dtype=np.int64)
    return np.asarray(obs, dtype=np.float64).reshape(1, -1)


def run_episodes(
    env: Any,
    learner: Learner,
    rng: np.random.Generator,
    episodes: int,
    sojourn: int = 1,
    learn: bool = True,
    explore: bool = True,
    max_steps: int = 10_000,
) -> np.ndarray:
    """Play ``episodes`` episodes, holding each action for ``sojourn`` env steps (one SMDP step) and learning
    from every SMDP step when ``learn``; returns each episode's undiscounted return.

    A step cut short by the episode's end pads its remaining rewards with 0 and is marked done; an episode
    truncated by the environment or by ``max_steps`` is not (its last state is bootstrapped).
    """
    check_int("episodes", episodes, 0)
    check_int("sojourn", sojourn, 1)
    returns = np.zeros(episodes)
    for e in range(episodes):
        obs, _ = env.reset(seed=int(rng.integers(2**31)))
        steps, over = 0, False
        while not over:
            x = _row(obs, learner)
            action = int(learner.act(x, rng, explore)[0])
            rewards = np.zeros((1, sojourn))
            terminated = truncated = False
            for i in range(sojourn):
                obs, r, terminated, truncated, _ = env.step(action)
                rewards[0, i] = r
                steps += 1
                if terminated or truncated or steps >= max_steps:
                    break
            returns[e] += rewards.sum()
            over = terminated or truncated or steps >= max_steps
            if learn:
                learner.learn(Transition(x, np.array([action]), rewards, _row(obs, learner),
                                         np.array([terminated])))
    return returns
