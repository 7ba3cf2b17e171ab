"""Running a learner on any Gymnasium environment (one agent) or PettingZoo parallel environment (every agent
through one shared learner, §4.2) with discrete actions, each action held for an SMDP step of ``sojourn``
environment steps."""

from __future__ import annotations

from typing import Any

import numpy as np

from confront.learning.base import Learner, Transition, check_int

__all__ = ["run_episodes", "run_parallel_episodes"]


def _row(obs: Any, learner: Learner) -> np.ndarray:
    if learner.observation == "discrete":
        return np.array([int(obs)], dtype=np.int64)
    return np.asarray(obs, dtype=np.float64).reshape(1, -1)


def run_episodes(env: Any, learner: Learner, rng: np.random.Generator, episodes: int, sojourn: int = 1,
                 learn: bool = True, explore: bool = True, max_steps: int = 10_000) -> np.ndarray:
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


def run_parallel_episodes(env: Any, learner: Learner, rng: np.random.Generator, episodes: int, sojourn: int = 1,
                          learn: bool = True, explore: bool = True, max_steps: int = 10_000) -> np.ndarray:
    """Like :func:`run_episodes` for a PettingZoo ``ParallelEnv``: all live agents act through ``learner`` and
    their SMDP transitions form one batch per step (parameter sharing). Returns the team's summed return per
    episode. An agent that ends inside a held step keeps its last observation and is marked done."""
    check_int("episodes", episodes, 0)
    check_int("sojourn", sojourn, 1)
    returns = np.zeros(episodes)
    for e in range(episodes):
        obs, _ = env.reset(seed=int(rng.integers(2**31)))
        steps = 0
        while env.agents and steps < max_steps:
            agents = list(env.agents)
            x = np.concatenate([_row(obs[ag], learner) for ag in agents])
            actions = learner.act(x, rng, explore)
            rewards = np.zeros((len(agents), sojourn))
            ended = np.zeros(len(agents), dtype=bool)
            last = dict(obs)
            for i in range(sojourn):
                live = {ag: int(a) for ag, a, gone in zip(agents, actions, ended, strict=True) if not gone}
                obs, rew, term, trunc, _ = env.step(live)
                steps += 1
                for k, ag in enumerate(agents):
                    if ag in live:
                        rewards[k, i] = rew.get(ag, 0.0)
                        last[ag] = obs.get(ag, last[ag])
                        ended[k] |= bool(term.get(ag, False))
                        if trunc.get(ag, False):
                            live.pop(ag)
                if not env.agents or steps >= max_steps:
                    break
            returns[e] += rewards.sum()
            if learn:
                nxt = np.concatenate([_row(last[ag], learner) for ag in agents])
                learner.learn(Transition(x, actions, rewards, nxt, ended))
    return returns
