"""Curriculum transfer (paper §5, Eq. 33-34): a frozen source policy guides a learner in the next task.

With probability eps(t) = eps(t0) exp(-p (t - t0)), floored, an agent acts from the source task's policy
(prior knowledge); otherwise from its current model. ``t`` counts ``learn`` calls (SMDP steps of the batch).
State and action spaces are the same in every task (Eq. 33), so a model carries over unchanged.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from confront.learning.base import Learner, Transition, check_int, check_range, require_keys

__all__ = ["CurriculumStage", "Frozen", "TransferParams", "TransferPolicy", "transfer_epsilon"]


def transfer_epsilon(t: float | np.ndarray, eps0: float, p: float, t0: float = 0.0, floor: float = 0.0
                     ) -> float | np.ndarray:
    """Probability of acting from the source policy at time ``t`` (eps0 before t0)."""
    dt = np.maximum(np.asarray(t, dtype=np.float64) - t0, 0.0)
    out = np.maximum(eps0 * np.exp(-p * dt), floor)  # Eq. 34: eps(t) = eps(t0) exp(-p t + p t0), floored
    return float(out) if out.ndim == 0 else out


@dataclass(frozen=True)
class TransferParams:
    """Eq. 34's settings: initial probability, decay coefficient p (per learn call), start time, floor."""

    eps0: float = 0.9
    decay: float = 0.01
    t0: int = 0
    floor: float = 0.05

    def __post_init__(self) -> None:
        check_range("eps0", self.eps0, 0.0, 1.0)
        check_range("decay", self.decay, 0.0, 1e6)
        check_int("t0", self.t0, 0)
        check_range("floor", self.floor, 0.0, self.eps0)

    def epsilon(self, t: float | np.ndarray) -> float | np.ndarray:
        """eps(t) with these settings."""
        return transfer_epsilon(t, self.eps0, self.decay, self.t0, self.floor)


@dataclass(frozen=True)
class CurriculumStage:
    """One task of a curriculum (source -> intermediate -> target): a scenario name and its length in rounds."""

    scenario: str
    rounds: int
    opponents: str = "td_team"

    def __post_init__(self) -> None:
        if not self.scenario:
            raise ValueError("bad value scenario='': must name a scenario")
        check_int("rounds", self.rounds, 1)


def _prefixed(prefix: str, state: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    return {f"{prefix}{k}": v for k, v in state.items()}


def _unprefixed(prefix: str, state: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    return {k[len(prefix):]: v for k, v in state.items() if k.startswith(prefix)}


class Frozen(Learner):
    """A learner that acts but no longer learns (a trained source policy or a frozen TD team)."""

    def __init__(self, inner: Learner) -> None:
        self.inner = inner
        self.kind = inner.kind
        self.params = inner.params
        self.observation = inner.observation
        self.n_actions = inner.n_actions

    def act(self, obs: np.ndarray, rng: np.random.Generator, explore: bool = True) -> np.ndarray:
        return self.inner.act(obs, rng, explore)

    def learn(self, batch: Transition) -> dict[str, float]:
        return {}

    def diagnostics(self) -> dict[str, float]:
        return self.inner.diagnostics()

    def state_dict(self) -> dict[str, np.ndarray]:
        return self.inner.state_dict()

    def load_state_dict(self, state: dict[str, np.ndarray]) -> None:
        self.inner.load_state_dict(state)


class TransferPolicy(Learner):
    """Acts from ``source`` (frozen, greedy) with probability eps(t), else from ``current``; trains ``current``.

    When not exploring (evaluation) it acts from ``current`` alone.
    """

    def __init__(self, current: Learner, source: Learner, params: TransferParams | None = None) -> None:
        if (current.observation, current.n_actions) != (source.observation, source.n_actions):
            raise ValueError(
                f"source ({source.observation}, {source.n_actions} actions) and current "
                f"({current.observation}, {current.n_actions} actions) differ: Eq. 33 needs the same spaces"
            )
        self.current = current
        self.source = source if isinstance(source, Frozen) else Frozen(source)
        self.transfer = params or TransferParams()
        self.kind = current.kind
        self.params = current.params
        self.observation = current.observation
        self.n_actions = current.n_actions
        self.t = 0

    def epsilon(self) -> float:
        """Current probability of acting from the source policy."""
        return float(self.transfer.epsilon(self.t))

    def act(self, obs: np.ndarray, rng: np.random.Generator, explore: bool = True) -> np.ndarray:
        own = self.current.act(obs, rng, explore)
        if not explore:
            return own
        prior = self.source.act(obs, rng, explore=False)
        use_prior = rng.random(own.shape[0]) < self.epsilon()
        return np.where(use_prior, prior, own)

    def learn(self, batch: Transition) -> dict[str, float]:
        out = self.current.learn(batch)
        self.t += 1
        return out

    def diagnostics(self) -> dict[str, float]:
        return {**self.current.diagnostics(), "transfer_epsilon": self.epsilon()}

    def state_dict(self) -> dict[str, np.ndarray]:
        return {**_prefixed("current.", self.current.state_dict()), **_prefixed("source.", self.source.state_dict()),
                "transfer_t": np.array(self.t, dtype=np.int64)}

    def load_state_dict(self, state: dict[str, np.ndarray]) -> None:
        require_keys(state, {"transfer_t": ()})
        self.current.load_state_dict(_unprefixed("current.", state))
        self.source.load_state_dict(_unprefixed("source.", state))
        self.t = int(state["transfer_t"])
