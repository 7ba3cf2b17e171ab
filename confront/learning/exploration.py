"""Action selection: Boltzmann/softmax with simulated annealing (Eq. 5-7), epsilon-greedy with the paper's
exploitation threshold, and epsilon-greedy with a decaying threshold.

The paper's epsilon is an *exploitation* threshold: with ``exploit = 0.9`` the agent acts greedily 90% of the
time and uniformly at random otherwise. Schedules are closed forms of a step counter, so a learner's only
exploration state is that counter.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from confront.learning.base import check_choice, check_range

__all__ = [
    "EXPLORATION_KINDS",
    "ExplorationParams",
    "anneal_temperature",
    "boltzmann_probs",
    "decayed_threshold",
    "epsilon_greedy",
    "epsilon_greedy_probs",
    "greedy",
    "policy_probs",
    "sample_categorical",
    "select_actions",
    "temperature_at",
]

EXPLORATION_KINDS = ("boltzmann", "egreedy", "degreedy")


def boltzmann_probs(q: np.ndarray, temperature: float) -> np.ndarray:
    """Softmax of ``q / temperature`` over the last axis, computed stably (max subtracted)."""
    z = np.asarray(q, dtype=np.float64) / temperature
    z = z - z.max(axis=-1, keepdims=True)  # Eq. 6: P(a|s) = exp(Q/T) / sum_k exp(Q_k/T), shift-invariant
    e = np.exp(z)
    return e / e.sum(axis=-1, keepdims=True)


def anneal_temperature(temperature: float, eta: float, t_min: float) -> float:
    """One annealing step."""
    return eta * (temperature - t_min) + t_min  # Eq. 7: T_{t+1} = eta (T_t - T_min) + T_min


def temperature_at(step: int | np.ndarray, t_max: float, t_min: float, eta: float) -> float | np.ndarray:
    """Temperature after ``step`` annealing steps, the closed form of Eq. 7 from T_0 = T_max."""
    return t_min + (t_max - t_min) * np.power(eta, step)  # Eq. 7 iterated: T_n = T_min + (T_max-T_min) eta^n


def decayed_threshold(step: int | np.ndarray, exploit: float, decay: float) -> float | np.ndarray:
    """Exploitation threshold after ``step`` decays: the exploration share 1 - exploit shrinks by ``decay``."""
    return 1.0 - (1.0 - exploit) * np.power(decay, step)  # Dgreedy: (1 - eps_t) = (1 - eps_0) d^t


def sample_categorical(probs: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """One draw per row of ``probs`` (rows sum to 1), by inverse CDF."""
    cdf = np.cumsum(probs, axis=-1)
    u = rng.random(cdf.shape[:-1])[..., None] * cdf[..., -1:]
    idx = (cdf <= u).sum(axis=-1)
    return np.minimum(idx, probs.shape[-1] - 1).astype(np.int64)


def greedy(q: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """Arg max per row, ties broken uniformly at random."""
    q = np.asarray(q)
    best = q == q.max(axis=-1, keepdims=True)
    return np.argmax(best * (1.0 + rng.random(q.shape)), axis=-1).astype(np.int64)


def epsilon_greedy(q: np.ndarray, exploit: float, rng: np.random.Generator) -> np.ndarray:
    """Greedy with probability ``exploit`` (the paper's threshold), else a uniform random action."""
    q = np.asarray(q)
    g = greedy(q, rng)
    rand = rng.integers(0, q.shape[-1], size=g.shape)
    return np.where(rng.random(g.shape) < exploit, g, rand)


def epsilon_greedy_probs(q: np.ndarray, exploit: float) -> np.ndarray:
    """Action probabilities of :func:`epsilon_greedy` (ties share the greedy mass)."""
    q = np.asarray(q, dtype=np.float64)
    best = (q == q.max(axis=-1, keepdims=True)).astype(np.float64)
    n = q.shape[-1]
    return exploit * best / best.sum(axis=-1, keepdims=True) + (1.0 - exploit) / n


@dataclass(frozen=True)
class ExplorationParams:
    """How actions are chosen while learning.

    ``boltzmann``: softmax at a temperature annealed from ``t_max`` to ``t_min`` by ``eta`` per step (Eq. 6-7);
    ``egreedy``: exploitation threshold ``exploit``; ``degreedy``: threshold rising as
    1 - (1 - exploit) * exploit_decay^step.
    """

    kind: str = "boltzmann"
    t_max: float = 0.1
    t_min: float = 0.01
    eta: float = 0.9
    exploit: float = 0.9
    exploit_decay: float = 0.99

    def __post_init__(self) -> None:
        check_choice("exploration", self.kind, EXPLORATION_KINDS)
        check_range("t_max", self.t_max, 0.0, np.inf, lo_open=True, hi_open=True)
        check_range("t_min", self.t_min, 0.0, self.t_max, lo_open=True)
        check_range("eta", self.eta, 0.0, 1.0)
        check_range("exploit", self.exploit, 0.0, 1.0)
        check_range("exploit_decay", self.exploit_decay, 0.0, 1.0)

    def temperature(self, step: int) -> float:
        """Softmax temperature at ``step``."""
        return float(temperature_at(step, self.t_max, self.t_min, self.eta))

    def threshold(self, step: int) -> float:
        """Exploitation threshold at ``step`` (constant for ``egreedy``)."""
        if self.kind == "degreedy":
            return float(decayed_threshold(step, self.exploit, self.exploit_decay))
        return self.exploit


def policy_probs(params: ExplorationParams, q: np.ndarray, step: int) -> np.ndarray:
    """The exploring policy's action probabilities pi(a|s) for each row of ``q``."""
    if params.kind == "boltzmann":
        return boltzmann_probs(q, params.temperature(step))
    return epsilon_greedy_probs(q, params.threshold(step))


def select_actions(
    params: ExplorationParams, q: np.ndarray, step: int, rng: np.random.Generator, explore: bool
) -> np.ndarray:
    """Sample from the exploring policy, or take the arg max (random ties) when not exploring."""
    if not explore:
        return greedy(q, rng)
    if params.kind == "boltzmann":
        return sample_categorical(boltzmann_probs(q, params.temperature(step)), rng)
    return epsilon_greedy(q, params.threshold(step), rng)
