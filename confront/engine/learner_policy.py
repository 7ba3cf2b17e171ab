"""A learner (``confront.learning``) as a bridge policy: evaluate it, or train it live in the real engine.

Each BridgeBot tank picks one of the paper's four moves every ``step_turns`` turns with the learner
(parameter sharing: one learner for every tank), the fixed gun/radar controller aims and fires every turn,
the per-turn reward is the paper's Eq. 35 on the tank's and its target's energies, and with
``train=True`` every finished SMDP step is passed to ``learner.learn`` at once (``done`` when the tank
died or the round ended).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from confront.arena.control import ControlConfig
from confront.arena.observe import ObservationConfig, reward_eq35
from confront.engine.bridge import Observation
from confront.engine.export import ExportedPolicy
from confront.learning.base import Learner, Transition


@dataclass
class _Pending:
    obs: np.ndarray
    action: int
    rewards: list[float] = field(default_factory=list)
    own: float = 100.0
    enemy: dict[str, float] = field(default_factory=dict)


class LearnerPolicy:
    """Bridge policy around a :class:`~confront.learning.base.Learner` (see the module docstring)."""

    def __init__(
        self,
        learner: Learner,
        rng: np.random.Generator,
        train: bool = True,
        explore: bool = True,
        observation: ObservationConfig | None = None,
        control: ControlConfig | None = None,
        step_turns: int = 4,
    ) -> None:
        if step_turns < 1:
            raise ValueError(f"step_turns must be >= 1, got {step_turns}")
        self.learner = learner
        self.rng = rng
        self.train = train
        self.explore = explore
        self.step_turns = step_turns
        self.obs_config = observation or ObservationConfig()
        # the twin supplies observations and the gun/radar controller; its Q table is never used
        self._twin = ExportedPolicy("qtable", q=np.zeros((320, 4)), observation=self.obs_config,
                                    control=control or ControlConfig(), step_turns=step_turns)
        self._pending: dict[tuple[str, int], _Pending] = {}
        self.updates = 0
        self.decisions = 0
        self.rewards: list[float] = []

    def _target_energy(self, obs: Observation) -> tuple[str, float] | None:
        es = obs.enemies()
        if not es:
            return None
        t = min(es, key=lambda s: (s.x - obs.x) ** 2 + (s.y - obs.y) ** 2)
        return t.name, t.energy

    def _learn(self, p: _Pending, next_obs: np.ndarray, done: bool) -> None:
        if self.train and p.rewards:
            rewards = np.array([p.rewards])
            self.learner.learn(Transition(p.obs, np.array([p.action]), rewards, next_obs, np.array([done])))
            self.updates += 1

    def __call__(self, obs: Observation) -> tuple[float, float, float, float, float]:
        key = (obs.robot, obs.round)
        p = self._pending.get(key)
        tgt = self._target_energy(obs)
        if p is not None:
            # Eq. 35 for the turn that just ended, against the current target's energy change
            if tgt is not None:
                prev_enemy = p.enemy.get(tgt[0], tgt[1])
                r = float(reward_eq35(np.array(p.own), np.array(obs.energy), np.array(prev_enemy),
                                      np.array(tgt[1]), self.obs_config.reward_guard))
            else:
                r = 0.0
            p.rewards.append(r)
            self.rewards.append(r)
            p.own = obs.energy
            p.enemy = {s.name: s.energy for s in obs.enemies()}
        ahead = turn = math.nan
        if (obs.turn - 1) % self.step_turns == 0:
            x = self._twin.learner_observation(obs, self.learner.observation)
            if p is not None:
                self._learn(p, x, done=False)
            action = int(self.learner.act(x, self.rng, explore=self.explore)[0])
            self.decisions += 1
            self._pending[key] = _Pending(x, action, own=obs.energy,
                                          enemy={s.name: s.energy for s in obs.enemies()})
            c = self._twin.control
            ahead, turn = {0: (c.move_distance, 0.0), 1: (-c.move_distance, 0.0),
                           2: (c.turn_move_distance, c.turn_angle),
                           3: (c.turn_move_distance, -c.turn_angle)}[action]
        gun, radar, fire = self._twin.gun_radar(obs)
        return (ahead, turn, gun, radar, fire)

    def end_episode(self, robot: str, round_: int) -> None:
        """The tank died or its round ended: learn its last step as terminal."""
        p = self._pending.pop((robot, round_), None)
        if p is not None:
            self._learn(p, p.obs, done=True)
