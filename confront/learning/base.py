"""The learner interface, the SMDP transition batch and parameter validation shared by every learner."""

from __future__ import annotations

import dataclasses
import math
from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any

import numpy as np

__all__ = [
    "Learner",
    "LearnerParams",
    "Transition",
    "check_choice",
    "check_int",
    "check_range",
    "params_from_dict",
    "require_keys",
]


@dataclass(frozen=True)
class Transition:
    """A batch of N SMDP transitions: the action was held for T turns and earned the T per-turn rewards.

    ``obs``/``next_obs`` are ``(N,)`` ints (discrete states) or ``(N, F)`` floats (features);
    ``action`` is ``(N,)`` ints; ``rewards`` is ``(N, T)`` (r_t .. r_{t+T-1}); ``done`` is ``(N,)`` bools
    (True when ``next_obs`` is terminal, so nothing is bootstrapped from it).
    """

    obs: np.ndarray
    action: np.ndarray
    rewards: np.ndarray
    next_obs: np.ndarray
    done: np.ndarray

    def __post_init__(self) -> None:
        rewards = np.asarray(self.rewards, dtype=np.float64)
        if rewards.ndim == 1:
            rewards = rewards[:, None]
        if rewards.ndim != 2 or rewards.shape[1] < 1:
            raise ValueError(f"rewards must have shape (N, T) with T >= 1, got {rewards.shape}")
        n = rewards.shape[0]
        action = np.asarray(self.action, dtype=np.int64).reshape(-1)
        done = np.asarray(self.done, dtype=bool).reshape(-1)
        obs = np.asarray(self.obs)
        next_obs = np.asarray(self.next_obs)
        for name, arr in (("action", action), ("done", done), ("obs", obs), ("next_obs", next_obs)):
            if arr.ndim == 0 or arr.shape[0] != n:
                raise ValueError(f"{name} has leading size {arr.shape[:1]}, expected {n} (rows of rewards)")
        if obs.shape != next_obs.shape:
            raise ValueError(f"obs shape {obs.shape} differs from next_obs shape {next_obs.shape}")
        object.__setattr__(self, "rewards", rewards)
        object.__setattr__(self, "action", action)
        object.__setattr__(self, "done", done)
        object.__setattr__(self, "obs", obs)
        object.__setattr__(self, "next_obs", next_obs)

    def __len__(self) -> int:
        return int(self.rewards.shape[0])

    @property
    def sojourn(self) -> int:
        """T, the number of turns the action was held."""
        return int(self.rewards.shape[1])

    @classmethod
    def from_team(
        cls,
        obs: np.ndarray,
        action: np.ndarray,
        rewards: np.ndarray,
        next_obs: np.ndarray,
        done: np.ndarray,
    ) -> Transition:
        """Stack a team's transitions, battle-major ``(B, R, ...)``, as rows ``(B*R, ...)`` (parameter sharing).

        ``rewards`` is ``(B, R, T)``; ``done`` may be ``(B,)`` (whole battle) or ``(B, R)``.
        """
        action = np.asarray(action)
        if action.ndim != 2:
            raise ValueError(f"team action must have shape (B, R), got {action.shape}")
        b, r = action.shape
        obs = np.asarray(obs)
        next_obs = np.asarray(next_obs)
        done = np.asarray(done, dtype=bool)
        if done.shape == (b,):
            done = np.repeat(done[:, None], r, axis=1)
        rewards = np.asarray(rewards, dtype=np.float64)
        return cls(
            obs=obs.reshape((b * r,) + obs.shape[2:]),
            action=action.reshape(b * r),
            rewards=rewards.reshape(b * r, -1),
            next_obs=next_obs.reshape((b * r,) + next_obs.shape[2:]),
            done=done.reshape(b * r),
        )


def check_range(
    key: str, value: float, lo: float, hi: float, lo_open: bool = False, hi_open: bool = False
) -> None:
    """Raise ValueError naming ``key`` when ``value`` is not a finite number in the interval."""
    ok = isinstance(value, int | float | np.floating | np.integer) and math.isfinite(float(value))
    if ok:
        v = float(value)
        ok = (v > lo if lo_open else v >= lo) and (v < hi if hi_open else v <= hi)
    if not ok:
        left = "(" if lo_open else "["
        right = ")" if hi_open else "]"
        raise ValueError(f"bad value {key}={value!r}: must be in {left}{lo}, {hi}{right}")


def check_int(key: str, value: int, lo: int, hi: float = math.inf) -> None:
    """Raise ValueError naming ``key`` when ``value`` is not an integer in [lo, hi]."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer) or not lo <= value <= hi:
        raise ValueError(f"bad value {key}={value!r}: must be an integer in [{lo}, {hi}]")


def check_choice(key: str, value: str, allowed: tuple[str, ...]) -> None:
    """Raise ValueError naming ``key`` when ``value`` is not one of ``allowed``."""
    if value not in allowed:
        raise ValueError(f"bad value {key}={value!r}: must be one of {', '.join(allowed)}")


@dataclass(frozen=True)
class LearnerParams:
    """Base of the learners' typed parameter dataclasses; subclasses validate in ``validate``."""

    def __post_init__(self) -> None:
        self.validate()

    def validate(self) -> None:
        """Raise ValueError on a bad value."""

    def to_dict(self) -> dict[str, Any]:
        """Plain JSON-compatible dictionary (tuples become lists)."""
        out = dataclasses.asdict(self)
        return {k: list(v) if isinstance(v, tuple) else v for k, v in out.items()}


def params_from_dict(cls: type[LearnerParams], values: dict[str, Any]) -> LearnerParams:
    """Build ``cls`` from a dictionary, rejecting unknown keys with a clear message."""
    names = {f.name for f in dataclasses.fields(cls)}
    for key in values:
        if key not in names:
            raise ValueError(f"unknown parameter {key!r} for {cls.__name__}: allowed {', '.join(sorted(names))}")
    fixed = {}
    for f in dataclasses.fields(cls):
        if f.name in values:
            v = values[f.name]
            fixed[f.name] = tuple(v) if isinstance(v, list) else v
    return cls(**fixed)


class Learner(ABC):
    """One interface for every learner (see docs/architecture.md, "Learners")."""

    kind: str  # the factory kind that builds this learner
    params: Any  # its typed parameter dataclass
    observation: str  # "discrete" or "features"
    n_actions: int

    @abstractmethod
    def act(self, obs: np.ndarray, rng: np.random.Generator, explore: bool = True) -> np.ndarray:
        """Actions ``(N,)`` for a batch of observations."""

    @abstractmethod
    def learn(self, batch: Transition) -> dict[str, float]:
        """Update from a batch of SMDP transitions; return this update's figures."""

    @abstractmethod
    def diagnostics(self) -> dict[str, float]:
        """Current temperature, learning rate, TD error, weights' norm, ..."""

    @abstractmethod
    def state_dict(self) -> dict[str, np.ndarray]:
        """Everything that changes while learning, as arrays (data only)."""

    @abstractmethod
    def load_state_dict(self, state: dict[str, np.ndarray]) -> None:
        """Restore from ``state_dict()`` output."""


def require_keys(state: dict[str, np.ndarray], expected: dict[str, tuple[int, ...]]) -> None:
    """Raise ValueError when a state dict misses a key or has an array of the wrong shape."""
    for key, shape in expected.items():
        if key not in state:
            raise ValueError(f"state_dict misses key {key!r}")
        got = np.shape(state[key])
        if got != shape:
            raise ValueError(f"state_dict key {key!r} has shape {got}, expected {shape}")
