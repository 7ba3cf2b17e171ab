"""The uniform random policy: a reference learner that acts uniformly at random and never learns.

It is the floor a learner must beat in a battle: same gun/radar controller, random macro moves.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from confront.learning.base import Learner, LearnerParams, Transition, check_choice, check_int, require_keys

__all__ = ["UniformParams", "UniformPolicy"]


@dataclass(frozen=True)
class UniformParams(LearnerParams):
    """Parameters of :class:`UniformPolicy`: the action count and which observations it is given."""

    n_actions: int = 4
    observation: str = "discrete"

    def validate(self) -> None:
        check_int("n_actions", self.n_actions, 1)
        check_choice("observation", self.observation, ("discrete", "features"))


class UniformPolicy(Learner):
    """Every action with probability 1 / n_actions, exploring or not; ``learn`` changes nothing."""

    def __init__(self, params: UniformParams | None = None, kind: str = "random") -> None:
        self.params = params or UniformParams()
        self.kind = kind
        self.observation = self.params.observation
        self.n_actions = self.params.n_actions

    def act(self, obs: np.ndarray, rng: np.random.Generator, explore: bool = True) -> np.ndarray:
        n = np.asarray(obs).shape[0]
        return np.asarray(rng.integers(0, self.n_actions, size=n), dtype=np.int64)

    def learn(self, batch: Transition) -> dict[str, float]:
        return {}

    def diagnostics(self) -> dict[str, float]:
        return {"temperature": float("inf"), "updates": 0.0}

    def state_dict(self) -> dict[str, np.ndarray]:
        return {"step": np.array(0, dtype=np.int64)}

    def load_state_dict(self, state: dict[str, np.ndarray]) -> None:
        require_keys(state, {"step": ()})
