"""Tabular Q-learning in the SMDP: SSAQ (Algorithm 1) and the TD team's epsilon-greedy Q-learning.

One implementation with options: exploration (Boltzmann with annealing, epsilon-greedy, decaying epsilon-greedy),
backup (the paper's Eq. 10 or the textbook SMDP backup), bootstrap (Boltzmann expectation of Eq. 9 or max of
Eq. 4) and learning rate (fixed or fuzzy). Several transitions of one batch that hit the same (s, a) are
averaged into one update, so a batch of many tanks and battles cannot overshoot. ``learn_one`` learns a single
transition given as Python numbers (a tank in the engine learns one SMDP step at a time) with the same result
bit for bit as ``learn`` on a batch of one, about 4x cheaper.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from confront.learning.backups import (
    BACKUPS,
    BOOTSTRAPS,
    bootstrap_values,
    pairwise_sum,
    paper_target_one,
    smdp_target,
)
from confront.learning.base import (
    Learner,
    LearnerParams,
    Transition,
    check_choice,
    check_int,
    check_range,
    require_keys,
)
from confront.learning.exploration import ExplorationParams, policy_probs, select_actions
from confront.learning.fuzzy import FuzzyLearningRate, FuzzyParams

__all__ = ["RATES", "TabularParams", "TabularQ", "table_update"]

RATES = ("fixed", "fuzzy")


def table_update(q: np.ndarray, s: np.ndarray, a: np.ndarray, step: np.ndarray) -> np.ndarray:
    """New table after adding ``step`` = alpha (target - Q) at (s, a); steps hitting one cell are averaged."""
    idx = s * q.shape[1] + a
    sums = np.bincount(idx, weights=step, minlength=q.size)
    counts = np.bincount(idx, minlength=q.size)
    return q + (sums / np.maximum(counts, 1)).reshape(q.shape)  # Eq. 4 / Eq. 10: Q <- Q + alpha (target - Q)


@dataclass(frozen=True)
class TabularParams(LearnerParams):
    """Parameters of :class:`TabularQ` (defaults: SSAQ with the paper's Table 1 values)."""

    n_states: int = 320
    n_actions: int = 4
    gamma: float = 0.9
    alpha: float = 0.3
    rate: str = "fixed"
    backup: str = "paper"
    bootstrap: str = "expected"
    exploration: str = "boltzmann"
    t_max: float = 0.1
    t_min: float = 0.01
    eta: float = 0.9
    exploit: float = 0.9
    exploit_decay: float = 0.99
    q_init: float = 0.0

    def validate(self) -> None:
        check_int("n_states", self.n_states, 1)
        check_int("n_actions", self.n_actions, 1)
        check_range("gamma", self.gamma, 0.0, 1.0)
        check_range("alpha", self.alpha, 0.0, 1.0, lo_open=True)
        check_choice("rate", self.rate, RATES)
        check_choice("backup", self.backup, BACKUPS)
        check_choice("bootstrap", self.bootstrap, BOOTSTRAPS)
        check_range("q_init", self.q_init, -1e12, 1e12)
        self.exploration_params()

    def exploration_params(self) -> ExplorationParams:
        """The exploration settings as their own dataclass."""
        return ExplorationParams(self.exploration, self.t_max, self.t_min, self.eta, self.exploit,
                                 self.exploit_decay)


class TabularQ(Learner):
    """Q table over discrete states; exploration schedules advance once per ``learn`` call."""

    observation = "discrete"

    def __init__(self, params: TabularParams | None = None, kind: str = "ssaq",
                 fuzzy: FuzzyParams | None = None) -> None:
        self.params = params or TabularParams()
        self.kind = kind
        self.n_actions = self.params.n_actions
        self._explore = self.params.exploration_params()
        self._fuzzy = FuzzyLearningRate(fuzzy) if self.params.rate == "fuzzy" else None
        self.q = np.full((self.params.n_states, self.n_actions), float(self.params.q_init))
        self.step = 0
        self._last = np.zeros(2)  # mean |TD error|, mean learning rate of the last update

    def _states(self, obs: np.ndarray, key: str) -> np.ndarray:
        s = np.asarray(obs).reshape(-1)
        if s.dtype.kind not in "iu":
            raise ValueError(f"{key} must be integer state indices for a tabular learner, got dtype {s.dtype}")
        if s.size and (s.min() < 0 or s.max() >= self.params.n_states):
            raise ValueError(f"{key} holds a state outside [0, {self.params.n_states})")
        return s

    def act(self, obs: np.ndarray, rng: np.random.Generator, explore: bool = True) -> np.ndarray:
        s = self._states(obs, "obs")
        return select_actions(self._explore, self.q[s], self.step, rng, explore)

    def learning_rate(self, rewards: np.ndarray) -> np.ndarray:
        """Per-transition RL rate: fixed alpha, or the fuzzy map of the SMDP step's summed reward."""
        if self._fuzzy is None:
            return np.full(rewards.shape[0], self.params.alpha)
        return np.asarray(self._fuzzy(rewards.sum(axis=1)))

    def targets(self, batch: Transition) -> np.ndarray:
        """Backup targets for the batch from the current table."""
        q_next = self.q[self._states(batch.next_obs, "next_obs")]
        probs = policy_probs(self._explore, q_next, self.step) if self.params.bootstrap == "expected" else None
        v = bootstrap_values(q_next, probs, batch.done)
        return smdp_target(batch.rewards, v, self.params.gamma, self.params.backup)

    def learn(self, batch: Transition) -> dict[str, float]:
        s = self._states(batch.obs, "obs")
        a = batch.action
        if a.size and (a.min() < 0 or a.max() >= self.n_actions):
            raise ValueError(f"action holds a value outside [0, {self.n_actions})")
        target = self.targets(batch)
        td = target - self.q[s, a]
        alpha = self.learning_rate(batch.rewards)
        self.q = table_update(self.q, s, a, alpha * td)
        self.step += 1
        self._last = np.array([np.abs(td).mean() if td.size else 0.0, alpha.mean() if alpha.size else 0.0])
        return {"td_error": float(self._last[0]), "learning_rate": float(self._last[1])}

    def learn_one(self, s: int, a: int, rewards: Sequence[float], s_next: int, done: bool) -> dict[str, float]:
        """``learn`` on the one transition (s, a, rewards r_t..r_{t+T-1}, s_next, done), given as Python numbers:
        the same table, step and statistics, bit for bit (the same operations in the same order on the same
        doubles: NumPy's exp on the four action values, its summation order by ``pairwise_sum``; tests check
        this), without the per-call array work of a batch of one."""
        n_states, n_actions = self.q.shape
        if not (0 <= s < n_states and 0 <= s_next < n_states):
            raise ValueError(f"state {s} or next state {s_next} outside [0, {n_states})")
        if not 0 <= a < n_actions:
            raise ValueError(f"action holds a value outside [0, {n_actions})")
        rewards = [float(r) for r in rewards]
        if not rewards:
            raise ValueError("rewards must have T >= 1 values")
        p = self.params
        v = 0.0 if done else self._bootstrap_one(self.q[s_next].tolist())  # bootstrap_values: 0 when done
        if p.backup == "paper":
            target = paper_target_one(rewards, v, p.gamma)
        else:
            target = float(smdp_target(np.array([rewards]), np.array([v]), p.gamma, p.backup)[0])
        q_sa = float(self.q[s, a])
        td = target - q_sa
        alpha = p.alpha if self._fuzzy is None else self._fuzzy.scalar(pairwise_sum(rewards))
        q = self.q + 0.0  # table_update: every other cell Q + 0 / 1, a new table
        q[s, a] = q_sa + (0.0 + alpha * td)  # and this one Q + (0 + step) / 1
        self.q = q
        self.step += 1
        self._last = np.array([abs(td), alpha])
        return {"td_error": float(self._last[0]), "learning_rate": float(self._last[1])}

    def _bootstrap_one(self, row: list[float]) -> float:
        """``bootstrap_values`` of one next state's action values (not done), as ``targets`` computes it."""
        if self.params.bootstrap != "expected":
            return max(row)
        explore = self._explore
        if explore.kind == "boltzmann":  # boltzmann_probs
            temp = explore.temperature(self.step)
            z = [x / temp for x in row]
            top = max(z)
            e = np.exp([x - top for x in z]).tolist()
            total = pairwise_sum(e)
            probs = [x / total for x in e]
        else:  # epsilon_greedy_probs
            exploit, top, n = explore.threshold(self.step), max(row), len(row)
            count = float(sum(x == top for x in row))
            probs = [exploit * (1.0 if x == top else 0.0) / count + (1.0 - exploit) / n for x in row]
        return pairwise_sum([pi * x for pi, x in zip(probs, row, strict=True)])

    def diagnostics(self) -> dict[str, float]:
        return {
            "temperature": self._explore.temperature(self.step),
            "exploit": self._explore.threshold(self.step),
            "learning_rate": float(self._last[1]),
            "td_error": float(self._last[0]),
            "weights_norm": float(np.linalg.norm(self.q)),
            "updates": float(self.step),
        }

    def state_dict(self) -> dict[str, np.ndarray]:
        return {"q": self.q.copy(), "step": np.array(self.step, dtype=np.int64), "last": self._last.copy()}

    def load_state_dict(self, state: dict[str, np.ndarray]) -> None:
        require_keys(state, {"q": self.q.shape, "step": (), "last": (2,)})
        self.q = np.array(state["q"], dtype=np.float64)
        self.step = int(state["step"])
        self._last = np.array(state["last"], dtype=np.float64)
